// The input format of the fuzz harnesses: the scene text, then zero or more "--set" overrides,
// separated by NUL bytes (a scene file never holds one: the parser rejects it as binary).
// The run harness (fuzz_run.cpp) takes one of the parts after the scene as a run-time inputs
// table instead (SplitRunInput).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace screwfem::fuzz {

struct Input {
  std::string scene;
  std::vector<std::string> overrides;
};

inline Input SplitInput(const std::uint8_t* data, std::size_t size) {
  Input in;
  const std::string all(reinterpret_cast<const char*>(data), size);
  std::size_t start = 0;
  for (bool first = true;; first = false) {
    const std::size_t nul = all.find('\0', start);
    std::string part =
        all.substr(start, nul == std::string::npos ? std::string::npos : nul - start);
    if (first)
      in.scene = std::move(part);
    else
      in.overrides.push_back(std::move(part));
    if (nul == std::string::npos || in.overrides.size() >= 8) break;
    start = nul + 1;
  }
  return in;
}

// The run harness's input: a part after the scene that starts as a table of run-time inputs
// does (its header 't,...' or 'time,...', a '#' comment or a blank line; an override starts
// with its key) is the table (the CLI's --inputs), the last such part if there are several.
struct RunInput {
  Input scene;
  bool has_table = false;
  std::string table;
};

inline RunInput SplitRunInput(const std::uint8_t* data, std::size_t size) {
  RunInput in;
  Input all = SplitInput(data, size);
  in.scene.scene = std::move(all.scene);
  for (std::string& part : all.overrides) {
    const bool table = part.rfind("t,", 0) == 0 || part.rfind("time,", 0) == 0 ||
                       part.rfind("#", 0) == 0 || part.rfind("\n", 0) == 0;
    if (table) {
      in.has_table = true;
      in.table = std::move(part);
    } else {
      in.scene.overrides.push_back(std::move(part));
    }
  }
  return in;
}

// Every InputError names the scene ("fuzz.yaml:LINE:COL: ..." or "fuzz.yaml: ..."): a message
// without it is a bug the harnesses report by aborting.
inline constexpr const char* kSource = "fuzz.yaml";

}  // namespace screwfem::fuzz
