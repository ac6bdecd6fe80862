#include "screwfem/io/input_table.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <unordered_map>

#include "read_file.h"
#include "scene_yaml.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

struct Cell {
  std::string text;
  int column = 1;  // 1-based character column of the cell's first character
};

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<Cell> SplitCells(const std::string& line) {
  std::vector<Cell> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    const std::string raw =
        line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const auto lead = raw.find_first_not_of(" \t");
    cells.push_back(
        {Trim(raw), static_cast<int>(start + (lead == std::string::npos ? 0 : lead)) + 1});
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return cells;
}

[[noreturn]] void Fail(const std::string& source, int line, int column, const std::string& what) {
  throw InputError(source + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " +
                   what);
}

}  // namespace

InputTable ParseInputTable(const std::string& text, const std::string& source, const Model& model) {
  InputTable table;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  bool header = false;
  std::size_t width = 0;
  // Names to indices once, and the columns seen: a header of n columns is read in time
  // linear in n (a linear search per column took 12.6 s for 1e5 inputs).
  std::vector<std::string> names;
  std::unordered_map<std::string, int> index_of;
  for (const ModelInput& i : model.inputs) {
    index_of.emplace(i.name, static_cast<int>(names.size()));
    names.push_back(i.name);
  }
  std::vector<char> has_column(names.size(), 0);
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = Trim(line);
    if (t.empty() || t[0] == '#') continue;
    const std::vector<Cell> cells = SplitCells(line);
    if (!header) {
      header = true;
      width = cells.size();
      if (cells[0].text != "t" && cells[0].text != "time")
        Fail(source, line_no, cells[0].column,
             "the first column is the time: expected the header 't,NAME,...', got '" +
                 cells[0].text + "'");
      if (cells.size() < 2)
        Fail(source, line_no, cells[0].column, "expected at least one input column after 't'");
      for (std::size_t c = 1; c < cells.size(); ++c) {
        const auto found = index_of.find(cells[c].text);
        const int index = found == index_of.end() ? -1 : found->second;
        if (index < 0)
          Fail(source, line_no, cells[c].column,
               "unknown input '" + cells[c].text + "'" +
                   (names.empty() ? std::string(" (the scene declares no inputs)")
                                  : scene_yaml::UnknownNameHint(cells[c].text, names)));
        if (has_column[static_cast<std::size_t>(index)])
          Fail(source, line_no, cells[c].column, "input '" + cells[c].text + "' has two columns");
        has_column[static_cast<std::size_t>(index)] = 1;
        table.inputs.push_back(index);
      }
      table.values.resize(table.inputs.size());
      continue;
    }
    if (cells.size() != width)
      Fail(source, line_no, 1,
           "expected " + std::to_string(width) + " values (t and one per input), got " +
               std::to_string(cells.size()));
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const std::string& s = cells[c].text;
      char* end = nullptr;
      errno = 0;
      const double x = s.empty() ? NAN : std::strtod(s.c_str(), &end);
      if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(x))
        Fail(source, line_no, cells[c].column, "expected a finite number, got '" + s + "'");
      if (c == 0) {
        if (!table.times.empty() && !(x > table.times.back()))
          Fail(source, line_no, cells[c].column, "times must be strictly increasing");
        table.times.push_back(x);
      } else {
        table.values[c - 1].push_back(x);
      }
    }
  }
  if (!header) Fail(source, 1, 1, "empty input table: expected the header 't,NAME,...'");
  if (table.times.empty()) Fail(source, line_no, 1, "expected at least one row of values");
  return table;
}

InputTable ReadInputTable(const std::string& path, const Model& model, const StopRequest& stop) {
  return ParseInputTable(
      io_detail::ReadFileWithLimit(path, kMaxInputTableBytes, "input table", stop), path, model);
}

void SetInputsAt(const InputTable& table, double t, Data& data) {
  if (table.empty()) return;
  const std::vector<double>& ts = table.times;
  std::size_t i = 0;  // the segment [ts[i], ts[i+1]) holding t, or a held end
  bool held = true;
  if (t >= ts.back()) {
    i = ts.size() - 1;
  } else if (t > ts.front()) {
    i = static_cast<std::size_t>(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin()) - 1;
    held = false;
  }
  // The arithmetic of a table profile (ProfileTerm::kTable), so that the two agree bit for bit.
  for (std::size_t c = 0; c < table.inputs.size(); ++c) {
    const std::vector<double>& v = table.values[c];
    if (held) {
      data.inputs(table.inputs[c]) = v[i];
    } else {
      const double slope = (v[i + 1] - v[i]) / (ts[i + 1] - ts[i]);
      data.inputs(table.inputs[c]) = v[i] + slope * (t - ts[i]);
    }
  }
}

}  // namespace screwfem
