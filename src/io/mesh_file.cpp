#include "screwfem/io/mesh_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

std::string MeshAt(const std::string& name, std::size_t line) {
  return name + ":" + std::to_string(line) + ": ";
}

std::string MeshReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool MeshEndsWith(std::string a, const std::string& b) {
  std::transform(a.begin(), a.end(), a.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return a.size() >= b.size() && a.compare(a.size() - b.size(), b.size(), b) == 0;
}

// A number from a token, or throws with the line.
double MeshNumber(const std::string& token, const std::string& where, const char* what) {
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  if (token.empty() || end != token.c_str() + token.size())
    throw InputError(where + "expected a number (" + what + "), got '" + token + "'");
  if (!std::isfinite(v))
    throw InputError(where + "expected a finite number (" + what + "), got '" + token + "'");
  return v;
}

TriangleMesh ParseObj(const std::string& text, const std::string& name) {
  TriangleMesh m;
  std::istringstream in(text);
  std::string line;
  std::size_t number = 0;
  std::vector<int> corners;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    if (!(ls >> key) || key[0] == '#') continue;
    const std::string where = MeshAt(name, number);
    if (key == "v") {
      std::string t[3];
      if (!(ls >> t[0] >> t[1] >> t[2])) throw InputError(where + "expected a vertex 'v x y z'");
      m.vertices.emplace_back(MeshNumber(t[0], where, "vertex x"),
                              MeshNumber(t[1], where, "vertex y"),
                              MeshNumber(t[2], where, "vertex z"));
    } else if (key == "f") {
      corners.clear();
      std::string c;
      while (ls >> c) {
        const std::string index = c.substr(0, c.find('/'));
        char* end = nullptr;
        const long i = std::strtol(index.c_str(), &end, 10);
        if (index.empty() || end != index.c_str() + index.size() || i == 0)
          throw InputError(where + "expected a vertex index (1-based, or negative), got '" + c +
                           "'");
        const long n = static_cast<long>(m.vertices.size());
        const long k = i > 0 ? i - 1 : n + i;
        if (k < 0 || k >= n)
          throw InputError(where + "vertex index " + std::to_string(i) + " out of range (" +
                           std::to_string(n) + " vertices so far)");
        corners.push_back(static_cast<int>(k));
      }
      if (corners.size() < 3)
        throw InputError(where + "expected a face of at least 3 vertices, got " +
                         std::to_string(corners.size()));
      for (std::size_t k = 1; k + 1 < corners.size(); ++k)
        m.faces.push_back({corners[0], corners[k], corners[k + 1]});
    }
  }
  if (m.faces.empty()) throw InputError(name + ": expected faces ('f' lines), found none");
  return m;
}

// STL has no shared vertices: each facet gets its own three (identical corners are not merged).
TriangleMesh ParseAsciiStl(const std::string& text, const std::string& name) {
  TriangleMesh m;
  std::istringstream in(text);
  std::string line;
  std::size_t number = 0;
  int pending = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream ls(line);
    std::string key;
    if (!(ls >> key)) continue;
    const std::string where = MeshAt(name, number);
    if (key == "vertex") {
      std::string t[3];
      if (!(ls >> t[0] >> t[1] >> t[2])) throw InputError(where + "expected 'vertex x y z'");
      m.vertices.emplace_back(MeshNumber(t[0], where, "vertex x"),
                              MeshNumber(t[1], where, "vertex y"),
                              MeshNumber(t[2], where, "vertex z"));
      ++pending;
    } else if (key == "endloop") {
      if (pending != 3)
        throw InputError(where + "expected 3 vertices in a facet's loop, got " +
                         std::to_string(pending));
      const int n = static_cast<int>(m.vertices.size());
      m.faces.push_back({n - 3, n - 2, n - 1});
      pending = 0;
    }
  }
  if (m.faces.empty()) throw InputError(name + ": expected facets, found none");
  return m;
}

TriangleMesh ParseBinaryStl(const std::string& text, const std::string& name) {
  std::uint32_t count = 0;
  std::memcpy(&count, text.data() + 80, 4);
  const std::size_t expected = 84 + 50 * static_cast<std::size_t>(count);
  if (text.size() < expected)
    throw InputError(name + ": truncated binary STL: its header gives " + std::to_string(count) +
                     " triangles, " + std::to_string(expected) + " bytes, the file has " +
                     std::to_string(text.size()));
  if (count == 0) throw InputError(name + ": the binary STL has no triangles");
  TriangleMesh m;
  m.vertices.reserve(3 * count);
  for (std::size_t t = 0; t < count; ++t) {
    const char* p = text.data() + 84 + 50 * t + 12;  // after the facet normal
    for (int k = 0; k < 3; ++k) {
      float v[3];
      std::memcpy(v, p + 12 * k, 12);
      const Vec3 x(v[0], v[1], v[2]);
      if (!x.allFinite())
        throw InputError(name + ": triangle " + std::to_string(t) + " has a non-finite vertex");
      m.vertices.push_back(x);
    }
    const int n = static_cast<int>(m.vertices.size());
    m.faces.push_back({n - 3, n - 2, n - 1});
  }
  return m;
}

}  // namespace

TriangleMesh ParseMeshText(const std::string& text, const std::string& name, bool obj) {
  if (obj) return ParseObj(text, name);
  // Binary unless it starts with 'solid' and holds 'facet' (binary headers may start with
  // 'solid' too), and its size matches no binary count.
  bool ascii = text.compare(0, 5, "solid") == 0 && text.find("facet") != std::string::npos;
  if (ascii && text.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, text.data() + 80, 4);
    if (84 + 50 * static_cast<std::size_t>(count) == text.size()) ascii = false;
  }
  if (ascii) return ParseAsciiStl(text, name);
  if (text.size() < 84)
    throw InputError(name + ": truncated binary STL: " + std::to_string(text.size()) +
                     " bytes, shorter than its 84-byte header");
  return ParseBinaryStl(text, name);
}

TriangleMesh ReadMeshFile(const std::string& path) {
  const bool obj = MeshEndsWith(path, ".obj");
  if (!obj && !MeshEndsWith(path, ".stl"))
    throw InputError(path + ": expected a mesh file ending in .stl or .obj");
  return ParseMeshText(MeshReadAll(path), path, obj);
}

std::vector<std::vector<double>> ReadHeightFile(const std::string& path) {
  const std::string text = MeshReadAll(path);
  std::istringstream in(text);
  std::string line;
  std::size_t number = 0;
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    ++number;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ls(line);
    std::string token;
    std::vector<double> row;
    while (ls >> token) {
      if (row.empty() && token[0] == '#') break;
      row.push_back(MeshNumber(token, MeshAt(path, number), "height"));
    }
    if (row.empty()) continue;
    if (!rows.empty() && row.size() != rows.front().size())
      throw InputError(MeshAt(path, number) + "expected " + std::to_string(rows.front().size()) +
                       " heights (as the first row), got " + std::to_string(row.size()));
    rows.push_back(std::move(row));
  }
  if (rows.size() < 2 || rows.front().size() < 2)
    throw InputError(path + ": expected a grid of at least 2 x 2 heights");
  return rows;
}

}  // namespace screwfem
