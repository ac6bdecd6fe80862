// Scene files (docs/scene-format.md): the reader turns the text into a SceneSpec
// (scene_reader.cpp), the compiler turns the spec into a Scene (scene_compiler.cpp).
#include "screwfem/io/scene.h"

#include "read_file.h"
#include "screwfem/io/scene_spec.h"
#include "screwfem/model/errors.h"

namespace screwfem {

Scene ParseScene(const std::string& yaml_text, const std::string& source_name,
                 const std::vector<std::string>& overrides) {
  SceneSources sources;
  const SceneSpec spec = ReadSceneSpec(yaml_text, source_name, overrides, &sources);
  return CompileScene(spec, sources);
}

SceneSpec LoadSceneSpec(const std::string& path, const std::vector<std::string>& overrides,
                        SceneSources* sources, const StopRequest& stop) {
  const std::string text = io_detail::ReadFileWithLimit(path, kMaxSceneBytes, "scene file", stop);
  return ReadSceneSpec(text, path, overrides, sources);
}

Scene LoadScene(const std::string& path, const std::vector<std::string>& overrides,
                const StopRequest& stop) {
  SceneSources sources;
  const SceneSpec spec = LoadSceneSpec(path, overrides, &sources, stop);
  return CompileScene(spec, sources);
}

}  // namespace screwfem
