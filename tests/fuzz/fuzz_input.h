// The input format of the fuzz harnesses: the scene text, then zero or more "--set" overrides,
// separated by NUL bytes (a scene file never holds one: the parser rejects it as binary).
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

// Every InputError names the scene ("fuzz.yaml:LINE:COL: ..." or "fuzz.yaml: ..."): a message
// without it is a bug the harnesses report by aborting.
inline constexpr const char* kSource = "fuzz.yaml";

}  // namespace screwfem::fuzz
