// The scene reference (docs/scene-format.md) and the scene reader hold the same keys.
//
// The keys the reader accepts have one source of truth: the lists it passes to CheckKeys, which
// also give the "unknown key" errors. The test reads scenes that reach every CheckKeys call of
// src/io/scene_reader*.cpp (the example scenes, tests/data and tests/io/data/every_key.yaml)
// with an observer installed (scene_yaml::SetKeyCheckObserver), so it sees every map the reader
// checks, its dotted path and the keys allowed there. The reference documents keys in tables
// whose first header cell is `key`; each map of the reader belongs to one or more sections of
// the page (kSections below). The test fails
//  - when a CheckKeys call of the reader is reached by none of the scenes (add what it reads to
//    every_key.yaml), or a map's path belongs to no section (add it to kSections);
//  - when a key the reader accepts is in none of the key tables of its sections (document it:
//    unit, default, error);
//  - when a key table lists a key that the reader does not accept in that section, or a
//    section has a key table that no map of the reader belongs to.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "io/scene_yaml.h"
#include "screwfem/io/scene_spec.h"

namespace screwfem::scene_reference_test {
namespace {

namespace fs = std::filesystem;

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A map of the reader, its path with entity names replaced by '*' and list indices by '[]':
// "bodies.arm.shapes[0]" -> "bodies.*.shapes[]".
std::string Pattern(const std::string& path) {
  std::vector<std::string> parts;
  std::string part;
  for (std::size_t i = 0; i <= path.size(); ++i) {
    if (i == path.size() || path[i] == '.') {
      parts.push_back(part);
      part.clear();
    } else {
      part += path[i];
    }
  }
  static const std::set<std::string> kNamed = {"points",    "materials", "sections", "bodies",
                                               "joints",    "loads",     "tendons",  "forces",
                                               "actuation", "inputs",    "robots"};
  if (parts.size() > 1 && kNamed.count(parts[0])) parts[1] = "*";
  if (parts.size() > 2 && ((parts[0] == "contact" && parts[1] == "obstacles") ||
                           (parts[0] == "outputs" && parts[1] == "points")))
    parts[2] = "*";
  if (parts.size() > 3 && parts[0] == "robots" && parts[2] == "joints") parts[3] = "*";
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    out += (i ? "." : "") + std::regex_replace(parts[i], std::regex(R"(\[[0-9]+\])"), "[]");
  }
  return out;
}

// Which sections of docs/scene-format.md (their headings) document the keys of a map: by the
// reader function for the maps that can appear in many places, else by the map's pattern.
struct SectionRule {
  std::string function;  // reader function, or "" to match by pattern
  std::string pattern;   // Pattern() of the map's path, or "" with a function
  std::vector<std::string> sections;
};
const std::vector<SectionRule> kSections = {
    {"UnitAxis", "", {"`joints`"}},
    {"ReadMaterial", "", {"`materials`"}},
    {"ReadProfile", "", {"Profiles"}},
    {"ReadProfileTerm", "", {"Profiles"}},
    {"ReadBodyPoint", "", {"Body points (eyelets and force-element ends)"}},
    {"ReadRoute", "", {"Routing helpers"}},
    {"", "", {"Top-level keys"}},
    {"", "defaults", {"`defaults`"}},
    {"", "sections.*", {"`sections`"}},
    {"", "bodies.*", {"Rigid bodies", "Soft bodies (rods)"}},
    {"", "bodies.*.initial_velocity", {"Initial state"}},
    {"", "bodies.*.shapes[]", {"`contact`"}},
    {"", "joints.*", {"`joints`"}},
    {"", "joints.*.drive", {"Drives"}},
    {"ReadOrientation", "", {"Orientations"}},
    {"", "robots.*", {"`robots`"}},
    {"", "robots.*.base", {"`robots`"}},
    {"", "robots.*.joints.*", {"`robots`"}},
    {"", "robots.*.joints.*.drive", {"Drives"}},
    {"", "loads.*", {"`loads`"}},
    {"", "tendons.*", {"`tendons`"}},
    {"", "forces.*", {"`forces`"}},
    {"", "actuation.*", {"`actuation`"}},
    {"", "contact", {"`contact`"}},
    {"", "contact.obstacles.*", {"`contact`"}},
    {"", "contact.pairs[]", {"`contact`"}},
    {"", "analysis", {"`analysis`"}},
    {"", "analysis.tolerance", {"`analysis`"}},
    {"", "analysis.tolerances", {"`analysis`"}},
    {"", "analysis.stop_at_rest", {"`analysis`"}},
    {"", "analysis.statics", {"`analysis.statics`"}},
    {"", "outputs", {"`outputs`"}},
    {"", "outputs.points.*", {"`outputs`"}},
};

const SectionRule* RuleFor(const std::string& function, const std::string& pattern) {
  for (const SectionRule& r : kSections)
    if (!r.function.empty() && function == r.function) return &r;
  for (const SectionRule& r : kSections)
    if (r.function.empty() && r.pattern == pattern) return &r;
  return nullptr;
}

// What the reader checked: per rule (index in kSections), the keys allowed; the call sites.
struct Observed {
  std::map<std::size_t, std::set<std::string>> keys;
  std::map<std::size_t, std::set<std::string>> paths;  // examples, for messages
  std::set<std::pair<std::string, int>> lines;         // CheckKeys calls reached: file, line
  std::set<std::string> unmapped;                      // "function: pattern"
};

void Observe(const scene_yaml::KeyCheck& check, void* context) {
  auto* o = static_cast<Observed*>(context);
  o->lines.emplace(std::filesystem::path(check.file).filename().string(), check.line);
  const std::string function = check.function;
  const std::string pattern = Pattern(check.path);
  const SectionRule* rule = RuleFor(function, pattern);
  if (rule == nullptr) {
    o->unmapped.insert(function + ": '" + check.path + "' (pattern '" + pattern + "')");
    return;
  }
  const std::size_t i = static_cast<std::size_t>(rule - kSections.data());
  o->keys[i].insert(check.allowed->begin(), check.allowed->end());
  o->paths[i].insert(check.path);
}

// Key tables of the reference: heading -> keys (the backquoted names in the first column of
// every table whose first header cell is "key", up to the next heading of any level).
std::map<std::string, std::set<std::string>> DocumentedKeys(const std::string& text) {
  std::map<std::string, std::set<std::string>> out;
  std::istringstream in(text);
  std::string line, heading;
  bool in_table = false, in_fence = false;
  const std::regex code("`([^`]+)`");
  while (std::getline(in, line)) {
    if (line.rfind("```", 0) == 0) in_fence = !in_fence;
    if (in_fence) continue;
    if (line.rfind("#", 0) == 0) {
      heading = line.substr(line.find_first_not_of('#'));
      heading = heading.substr(heading.find_first_not_of(' '));
      in_table = false;
      continue;
    }
    if (line.rfind("|", 0) != 0) {
      in_table = false;
      continue;
    }
    std::string first = line.substr(1, line.find('|', 1) - 1);
    first.erase(0, first.find_first_not_of(' '));
    first.erase(first.find_last_not_of(' ') + 1);
    if (!in_table) {
      in_table = first == "key";
      if (in_table) out[heading];  // a key table, even if empty
      continue;
    }
    if (first.rfind("---", 0) == 0) continue;
    for (auto it = std::sregex_iterator(first.begin(), first.end(), code);
         it != std::sregex_iterator(); ++it)
      out[heading].insert((*it)[1].str());
  }
  return out;
}

std::string Join(const std::set<std::string>& s, std::size_t at_most = 1000) {
  std::string out;
  std::size_t n = 0;
  for (const std::string& x : s) {
    if (n++ == at_most) return out + ", ...";
    out += (out.empty() ? "" : ", ") + x;
  }
  return out;
}

class SceneReference : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const fs::path root = SCREWFEM_SOURCE_DIR;
    std::vector<fs::path> scenes;
    const std::vector<fs::path> dirs = {root / "examples", root / "tests" / "data",
                                        root / "tests" / "io" / "data"};
    for (const fs::path& dir : dirs)
      for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.path().extension() == ".yaml") scenes.push_back(e.path());
    std::sort(scenes.begin(), scenes.end());
    observed_ = new Observed;
    scene_yaml::SetKeyCheckObserver(&Observe, observed_);
    for (const fs::path& scene : scenes) {
      try {
        SceneSources sources;
        ReadSceneSpec(ReadFile(scene), scene.string(), {}, &sources);
      } catch (const std::exception& e) {
        errors_ += scene.string() + ": " + e.what() + "\n";
      }
    }
    scene_yaml::SetKeyCheckObserver(nullptr, nullptr);
    for (const char* name : {"scene_reader.cpp", "scene_reader_items.cpp",
                             "scene_reader_analysis.cpp", "scene_reader_robots.cpp"})
      reader_sources_[name] = ReadFile(root / "src" / "io" / name);
    docs_ = DocumentedKeys(ReadFile(root / "docs" / "scene-format.md"));
  }
  static void TearDownTestSuite() {
    delete observed_;
    observed_ = nullptr;
  }

  static Observed* observed_;
  static std::string errors_;
  static std::map<std::string, std::string> reader_sources_;  // the reader's files by name
  static std::map<std::string, std::set<std::string>> docs_;
};
Observed* SceneReference::observed_ = nullptr;
std::string SceneReference::errors_;
std::map<std::string, std::string> SceneReference::reader_sources_;
std::map<std::string, std::set<std::string>> SceneReference::docs_;

TEST_F(SceneReference, TheScenesReadAndReachEveryKeyCheck) {
  EXPECT_EQ(errors_, "") << "every scene read must succeed";
  std::vector<std::pair<std::string, int>> calls;
  for (const auto& [name, text] : reader_sources_) {
    std::istringstream in(text);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n)
      if (line.find("CheckKeys(") != std::string::npos) calls.emplace_back(name, n);
  }
  ASSERT_FALSE(calls.empty());
  for (const auto& call : calls)
    EXPECT_TRUE(observed_->lines.count(call))
        << "src/io/" << call.first << ":" << call.second
        << ": this CheckKeys call is reached by no scene; add what it reads to "
           "tests/io/data/every_key.yaml";
  EXPECT_EQ(observed_->lines.size(), calls.size())
      << "calls reached at other lines than those holding 'CheckKeys(' (a call split over lines?)";
  EXPECT_TRUE(observed_->unmapped.empty())
      << "maps of the reader that belong to no section of the reference (add them to kSections): "
      << Join(observed_->unmapped);
}

TEST_F(SceneReference, EveryKeyTheReaderAcceptsIsDocumented) {
  for (const auto& [i, keys] : observed_->keys) {
    std::set<std::string> documented;
    for (const std::string& section : kSections[i].sections) {
      const auto d = docs_.find(section);
      ASSERT_NE(d, docs_.end()) << "docs/scene-format.md has no key table under '" << section
                                << "'";
      documented.insert(d->second.begin(), d->second.end());
    }
    for (const std::string& key : keys)
      EXPECT_TRUE(documented.count(key))
          << "key '" << key << "' of " << Join(observed_->paths.at(i), 3)
          << " is in no key table of docs/scene-format.md, section(s) '"
          << kSections[i].sections.front() << "'"
          << (kSections[i].sections.size() > 1 ? ", ..." : "")
          << ": document it (unit, default, error)";
  }
}

TEST_F(SceneReference, EveryDocumentedKeyIsAccepted) {
  std::map<std::string, std::set<std::string>> accepted;  // section -> keys
  for (const auto& [i, keys] : observed_->keys)
    for (const std::string& section : kSections[i].sections)
      accepted[section].insert(keys.begin(), keys.end());
  for (const auto& [section, keys] : docs_) {
    const auto a = accepted.find(section);
    if (a == accepted.end()) {
      ADD_FAILURE() << "docs/scene-format.md, '" << section
                    << "': a key table that belongs to no map of the reader (keys " << Join(keys)
                    << "; add the map to kSections)";
      continue;
    }
    for (const std::string& key : keys)
      EXPECT_TRUE(a->second.count(key))
          << "docs/scene-format.md, '" << section << "' documents key '" << key
          << "', which the reader does not accept there (it accepts " << Join(a->second) << ")";
  }
}

TEST(ScenePattern, NamesAndIndices) {
  EXPECT_EQ(Pattern(""), "");
  EXPECT_EQ(Pattern("bodies.arm.shapes[0]"), "bodies.*.shapes[]");
  EXPECT_EQ(Pattern("contact.obstacles.ground"), "contact.obstacles.*");
  EXPECT_EQ(Pattern("outputs.points.tip"), "outputs.points.*");
  EXPECT_EQ(Pattern("analysis.statics"), "analysis.statics");
}

}  // namespace
}  // namespace screwfem::scene_reference_test
