// Triangle meshes and height fields from files (docs/scene-format.md, contact obstacles of type
// mesh and heightfield): small readers of our own, no library (docs/numerics.md, "Triangle
// meshes": why not assimp).
#pragma once

#include <string>
#include <vector>

#include "screwfem/model/mesh.h"

namespace screwfem {

// A mesh from an STL (ASCII or binary; .stl) or Wavefront OBJ (.obj: `v x y z` and `f` lines,
// polygons fan-triangulated from their first corner, indices 1-based or negative = relative,
// `a/b/c` corners take the vertex index; other records ignored) file, the kind told by the
// extension (any case). Throws InputError naming the file, the line (OBJ, ASCII STL) and what
// was expected: a bad or out-of-range index, a non-finite vertex, a face of fewer than three
// corners, a truncated binary STL (its byte count against the 84 + 50 n of its header), no
// triangles.
TriangleMesh ReadMeshFile(const std::string& path);
// The same from text already read (`name` for the messages; `obj`: OBJ, else STL).
TriangleMesh ParseMeshText(const std::string& text, const std::string& name, bool obj);

// A height field from a CSV file: one row of the grid per line (numbers separated by commas
// or spaces; blank lines and lines starting with '#' skipped), every row of the same length,
// at least 2 x 2. Throws InputError naming the file and line.
std::vector<std::vector<double>> ReadHeightFile(const std::string& path);

}  // namespace screwfem
