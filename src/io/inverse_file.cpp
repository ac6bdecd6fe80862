// Inverse statics from a targets file (io/inverse_file.h, docs/inverse.md "From the command
// line").
#include "screwfem/io/inverse_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "read_file.h"
#include "scene_yaml.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

constexpr std::size_t kMaxTargetsFileBytes = 64u << 20;

// The node and offset of a scene point (outputs.points) as an effector (a rod point must be on
// a node).
InverseTarget EffectorOf(const Scene& scene, const OutputPoint& p) {
  if (p.rod < 0) return {p.node, p.offset, Vec3::Zero()};
  const Rod& rod = scene.model.rods[static_cast<std::size_t>(p.rod)];
  double arc = 0.0;
  for (int e = 0; e <= rod.num_elements; ++e) {
    if (std::abs(arc - p.arc_length) <= 1e-9 * std::max(1.0, rod.length))
      return {rod.nodes[static_cast<std::size_t>(e)], Vec3::Zero(), Vec3::Zero()};
    if (e < rod.num_elements)
      arc += scene.model.elements[static_cast<std::size_t>(rod.first_element + e)].length;
  }
  return {-1, Vec3::Zero(), Vec3::Zero()};
}

}  // namespace

InverseFile ParseInverseFile(const std::string& text, const std::string& source,
                             const Scene& scene) {
  const scene_yaml::Node root = scene_yaml::Parse(text, source);
  const scene_yaml::Reader r(source);
  const Model& m = scene.model;
  r.ExpectMap(root, "");
  r.CheckKeys(root, "", {"parameters", "targets", "tolerance"});
  InverseFile f;
  f.options.statics = scene.analysis.statics;
  if (const scene_yaml::Node* tol = root.Find("tolerance"))
    f.options.tolerance = r.PositiveNumber(*tol, "tolerance");
  // parameters: a list of {input|tendon|actuator|joint: NAME, lower, upper}.
  const scene_yaml::Node& params = r.Require(root, "", "parameters");
  if (!params.IsSequence() || params.items.empty())
    r.Fail(params.location, "parameters",
           "expected a list of parameters, got " + scene_yaml::Describe(params));
  for (std::size_t i = 0; i < params.items.size(); ++i) {
    const scene_yaml::Node& p = params.items[i];
    const std::string path = "parameters[" + std::to_string(i) + "]";
    r.ExpectMap(p, path);
    r.CheckKeys(p, path, {"input", "tendon", "actuator", "joint", "lower", "upper"});
    const std::vector<std::pair<std::string, ParameterKind>> kinds = {
        {"input", ParameterKind::kInput},
        {"tendon", ParameterKind::kTendonTension},
        {"actuator", ParameterKind::kActuator},
        {"joint", ParameterKind::kJointDrive}};
    int found = 0;
    for (const auto& [key, kind] : kinds) {
      const scene_yaml::Node* name = p.Find(key);
      if (!name) continue;
      ++found;
      const std::string n = r.Text(*name, path + "." + key);
      int index = -1;
      std::vector<std::string> known;
      switch (kind) {
        case ParameterKind::kInput:
          index = m.FindInput(n);
          for (const auto& x : m.inputs) known.push_back(x.name);
          break;
        case ParameterKind::kTendonTension:
          index = m.FindTendon(n);
          for (const auto& x : m.tendons) known.push_back(x.name);
          break;
        case ParameterKind::kActuator:
          index = m.FindActuator(n);
          for (const auto& x : m.actuators) known.push_back(x.name);
          break;
        default:
          index = m.FindJoint(n);
          for (const auto& x : m.joints) known.push_back(x.name);
          break;
      }
      if (index < 0)
        r.Fail(name->location, path + "." + key,
               "the scene has no " + key + " '" + n + "'" + scene_yaml::UnknownNameHint(n, known));
      Parameter param(kind, index, -1);
      try {
        ValidateParameter(m, param, "parameter");
      } catch (const InputError& e) {
        r.Fail(name->location, path + "." + key, e.what());
      }
      f.parameters.push_back(param);
      f.names.push_back(key + " " + n);
    }
    if (found != 1)
      r.Fail(p.location, path, "give exactly one of input, tendon, actuator or joint");
    const double inf = std::numeric_limits<double>::infinity();
    const scene_yaml::Node* lo = p.Find("lower");
    const scene_yaml::Node* hi = p.Find("upper");
    const double lower = lo ? r.Number(*lo, path + ".lower") : -inf;
    const double upper = hi ? r.Number(*hi, path + ".upper") : inf;
    if (!(lower <= upper))
      r.Fail(hi ? hi->location : p.location, path + ".upper", "must be >= lower");
    f.lower.conservativeResize(static_cast<Eigen::Index>(f.parameters.size()));
    f.upper.conservativeResize(static_cast<Eigen::Index>(f.parameters.size()));
    f.lower(f.lower.size() - 1) = lower;
    f.upper(f.upper.size() - 1) = upper;
  }
  // targets: a list of maps point -> [x, y, z], the same points in every entry.
  const scene_yaml::Node& targets = r.Require(root, "", "targets");
  if (!targets.IsSequence() || targets.items.empty())
    r.Fail(targets.location, "targets",
           "expected a list of targets ({POINT: [x, y, z]}), got " + scene_yaml::Describe(targets));
  std::vector<std::string> point_names;
  for (const OutputPoint& p : scene.outputs.points) point_names.push_back(p.name);
  for (std::size_t i = 0; i < targets.items.size(); ++i) {
    const scene_yaml::Node& t = targets.items[i];
    const std::string path = "targets[" + std::to_string(i) + "]";
    r.ExpectMap(t, path);
    if (t.entries.empty()) r.Fail(t.location, path, "expected at least one point");
    std::vector<InverseTarget> solve;
    std::vector<std::string> names;
    for (const auto& [entry, value] : t.entries) {
      const std::string field = path + "." + entry.key;
      const OutputPoint* point = nullptr;
      for (const OutputPoint& p : scene.outputs.points)
        if (p.name == entry.key) point = &p;
      if (!point)
        r.Fail(entry.key_location, field,
               "the scene has no point '" + entry.key + "' (its outputs.points)" +
                   scene_yaml::UnknownNameHint(entry.key, point_names));
      InverseTarget target = EffectorOf(scene, *point);
      if (target.node < 0)
        r.Fail(entry.key_location, field,
               "the point lies between the nodes of its rod (an effector must be on a node)");
      target.target = r.Vector3(value, field);
      solve.push_back(target);
      names.push_back(entry.key);
    }
    if (i == 0)
      f.points = names;
    else if (names != f.points)
      r.Fail(t.location, path, "every target must name the same points as the first, in order");
    f.solves.push_back(solve);
  }
  return f;
}

InverseFile LoadInverseFile(const std::string& path, const Scene& scene) {
  const std::string text =
      io_detail::ReadFileWithLimit(path, kMaxTargetsFileBytes, "targets file", StopRequest{});
  return ParseInverseFile(text, path, scene);
}

InverseRunResult RunInverseFile(const Scene& scene, const InverseFile& file,
                                const std::string& outdir) {
  std::error_code ec;
  std::filesystem::create_directories(outdir, ec);
  const std::string csv_path = (std::filesystem::path(outdir) / "inverse.csv").string();
  std::ofstream csv(csv_path);
  if (!csv) throw InputError(csv_path + ": cannot write the results");
  csv << "target,reached,distance";
  for (const std::string& n : file.names) {
    std::string column = n;
    std::replace(column.begin(), column.end(), ' ', '_');
    csv << ',' << column;
  }
  for (const std::string& p : file.points) csv << ',' << p << "_x," << p << "_y," << p << "_z";
  csv << '\n';
  Data data = MakeData(scene.model);
  // Start: zero offsets, and the inputs' own values (within the bounds).
  Eigen::VectorXd values = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(file.parameters.size()));
  for (std::size_t i = 0; i < file.parameters.size(); ++i)
    if (file.parameters[i].kind == ParameterKind::kInput)
      values(static_cast<Eigen::Index>(i)) = data.inputs(file.parameters[i].index);
  InverseRunResult out;
  char buf[64];
  for (std::size_t k = 0; k < file.solves.size(); ++k) {
    const InverseStaticsResult r =
        SolveInverseStatics(scene.model, data, file.parameters, file.lower, file.upper,
                            file.solves[k], values, file.options);
    if (r.values.size() == values.size()) values = r.values;
    (r.converged ? out.reached : out.unreachable) += 1;
    if (!r.converged) out.message += "target " + std::to_string(k) + ": " + r.message + "\n";
    csv << k << ',' << (r.converged ? 1 : 0);
    std::snprintf(buf, sizeof buf, ",%.17g", r.distance);
    csv << buf;
    for (Eigen::Index i = 0; i < values.size(); ++i) {
      std::snprintf(buf, sizeof buf, ",%.17g", values(i));
      csv << buf;
    }
    for (const InverseTarget& t : file.solves[k]) {
      const Vec3 x = data.H[static_cast<std::size_t>(t.node)].Act(t.offset);
      for (int c = 0; c < 3; ++c) {
        std::snprintf(buf, sizeof buf, ",%.17g", x(c));
        csv << buf;
      }
    }
    csv << '\n';
  }
  csv.flush();
  if (!csv) throw InputError(csv_path + ": cannot write the results");
  return out;
}

}  // namespace screwfem
