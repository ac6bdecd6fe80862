// Scene files (docs/scene-format.md): the reader turns the text into a SceneSpec
// (scene_reader.cpp), the compiler turns the spec into a Scene (scene_compiler.cpp).
#include "screwfem/io/scene.h"

#include <filesystem>
#include <fstream>

#include "screwfem/io/scene_spec.h"
#include "screwfem/model/errors.h"

namespace screwfem {

Scene ParseScene(const std::string& yaml_text, const std::string& source_name,
                 const std::vector<std::string>& overrides) {
  SceneSources sources;
  const SceneSpec spec = ReadSceneSpec(yaml_text, source_name, overrides, &sources);
  return CompileScene(spec, sources);
}

namespace {

// The text of a scene file, read with the size limit.
std::string ReadSceneFile(const std::string& path) {
  if (path.find('\0') != std::string::npos)
    throw InputError("scene path '" + std::string(path.c_str()) +
                     "...': contains a NUL character (not a file name)");
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path + ": is a directory, not a scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the scene file");
  // Bounded reads: a file without a size (/dev/zero, a pipe) stops at the limit.
  std::string text;
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof buffer);
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxSceneBytes)
      throw InputError(path + ": the scene file is larger than " +
                       std::to_string(kMaxSceneBytes >> 20) + " MiB (the limit)");
  }
  if (in.bad()) throw InputError(path + ": cannot read the scene file");
  return text;
}

}  // namespace

SceneSpec LoadSceneSpec(const std::string& path, const std::vector<std::string>& overrides,
                        SceneSources* sources) {
  return ReadSceneSpec(ReadSceneFile(path), path, overrides, sources);
}

Scene LoadScene(const std::string& path, const std::vector<std::string>& overrides) {
  SceneSources sources;
  const SceneSpec spec = LoadSceneSpec(path, overrides, &sources);
  return CompileScene(spec, sources);
}

}  // namespace screwfem
