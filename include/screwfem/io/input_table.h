// A table of run-time input values over time (the CLI's `screwfem run --inputs table.csv`).
//
// CSV text: a header row `t,NAME,NAME,...` (the first column is the time [s], each other column
// one of the scene's inputs by name), then one row per time, times strictly increasing. Blank
// lines and lines starting with '#' are skipped. Between rows a value is interpolated linearly;
// before the first row and after the last it is held. Inputs without a column keep their
// values (the scene's defaults). See docs/scene-format.md, "Run-time inputs".
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "screwfem/model/data.h"
#include "screwfem/solve/stop.h"

namespace screwfem {

struct InputTable {
  std::vector<int> inputs;                  // Model::inputs index of each value column
  std::vector<double> times;                // [s], strictly increasing
  std::vector<std::vector<double>> values;  // values[column][row]
  bool empty() const { return inputs.empty(); }
};

// Parses the CSV text for `model`'s inputs. Throws InputError "SOURCE:LINE:COLUMN: what was
// expected" for malformed numbers, ragged rows, times not increasing, an unknown input name or
// a repeated column.
InputTable ParseInputTable(const std::string& text, const std::string& source, const Model& model);
// The largest input table file ReadInputTable reads (docs/limits.md).
inline constexpr std::size_t kMaxInputTableBytes = std::size_t{64} << 20;  // 64 MiB

// Reads and parses a file of at most kMaxInputTableBytes, polling `stop` while reading.
// InputError "PATH: is a directory, not an input table" / "PATH: cannot open the input table" /
// "PATH: the input table is larger than 64 MiB (the limit)" (a file without a size, /dev/zero
// or a pipe, stops there) / "PATH: reading the input table was interrupted", and those of
// ParseInputTable.
InputTable ReadInputTable(const std::string& path, const Model& model,
                          const StopRequest& stop = {});

// data.inputs of the table's columns at time t (linear between rows, held outside them). No
// allocation.
void SetInputsAt(const InputTable& table, double t, Data& data);

}  // namespace screwfem
