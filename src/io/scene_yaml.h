// Internal to screwfem::io: the YAML document tree of a scene file, with the source location of
// every node, and the typed readers that turn it into values with "FILE:LINE:COL: FIELD: what
// was expected" messages (docs/scene-format.md, "Errors").
//
// The tree is built from yaml-cpp's event parser rather than YAML::Node so that every map key
// keeps its own location, duplicate keys are seen (YAML::Node keeps the first silently) and
// alias expansion is bounded.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "screwfem/io/scene_spec.h"
#include "screwfem/lie/se3.h"
#include "screwfem/model/enum_names.h"

namespace screwfem::scene_yaml {

// Where a node came from: a line and column of the scene file (1-based), or an override string
// (shared by all the nodes it wrote, so that an override costs memory linear in its length).
using Location = SourceLocation;

// Named values of a scene's `parameters:` block, in file order (docs/scene-format.md,
// "Parameters and expressions").
using ParameterTable = std::vector<std::pair<std::string, double>>;

struct MapEntry {
  std::string key;
  Location key_location;
};

struct Node {
  enum class Kind { kNull, kScalar, kSequence, kMap };
  Kind kind = Kind::kNull;
  Location location;
  std::string scalar;                              // kScalar
  bool quoted = false;                             // kScalar written in quotes
  std::vector<Node> items;                         // kSequence
  std::vector<std::pair<MapEntry, Node>> entries;  // kMap, in file order (duplicates kept)

  // Declared here and defaulted below, where Node is complete: the implicit ones would
  // instantiate std::pair<MapEntry, Node> while Node is still incomplete (Clang rejects that).
  Node();
  Node(const Node&);
  Node(Node&&) noexcept;
  Node& operator=(const Node&);
  Node& operator=(Node&&) noexcept;
  ~Node();

  bool IsNull() const { return kind == Kind::kNull; }
  bool IsScalar() const { return kind == Kind::kScalar; }
  bool IsSequence() const { return kind == Kind::kSequence; }
  bool IsMap() const { return kind == Kind::kMap; }
  // First entry with this key, or nullptr (maps only).
  const Node* Find(const std::string& key) const;
  Node* Find(const std::string& key);
  const MapEntry* FindEntry(const std::string& key) const;
};

inline Node::Node() = default;
inline Node::Node(const Node&) = default;
inline Node::Node(Node&&) noexcept = default;
inline Node& Node::operator=(const Node&) = default;
inline Node& Node::operator=(Node&&) noexcept = default;
inline Node::~Node() = default;

// Text of a location for messages: "FILE:LINE:COL" or "FILE: override 'a.b=c'".
std::string Where(const std::string& source, const Location& location);

// Kind of a node in words ("a map", "a list", "a number or text", "nothing").
std::string Describe(const Node& node);

// Parses one YAML document. Throws InputError for empty input (unless allow_empty: then a null
// node), invalid YAML, binary content, more than one document, non-scalar keys, or a tree
// beyond the size limits.
Node Parse(const std::string& text, const std::string& source, bool allow_empty = false);

// Applies "a.b.c=value" to the tree (value parsed as a YAML scalar or flow collection).
// Missing keys are created, except entries of the named collections in `collections` (dotted
// paths such as "bodies"), which must exist unless they are the last component. An empty value
// ("a.b.c=") removes the key, so that the reader takes its default (nothing happens when the
// key is not there; an item of a list cannot be removed). Time and
// memory are linear in the override's length; the key path has at most kMaxOverrideDepth
// components.
inline constexpr std::size_t kMaxOverrideDepth = 16;
void ApplyOverride(Node& root, const std::string& override_text, const std::string& source,
                   const std::vector<std::string>& collections);

// Closest candidate by edit distance, or "" when nothing is close.
std::string Closest(const std::string& word, const std::vector<std::string>& candidates);
// " (did you mean 'x'?)" or "".
std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates);
// DidYouMean, or when no candidate is close " (known: a, b, c)" (the first few).
std::string UnknownNameHint(const std::string& word, const std::vector<std::string>& candidates);

// ---------------------------------------------------------------------------------------------
// Typed reading with messages. A Reader knows the source name; `path` is the dotted field name
// used in messages (e.g. "bodies.arm56.elements").
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}
  const std::string& source() const { return source_; }

  [[noreturn]] void Fail(const Location& at, const std::string& path,
                         const std::string& what) const;

  // Checks that `node` is a map whose keys are all in `allowed` and not repeated; the first
  // offending key (in file order) is reported.
  void ExpectMap(const Node& node, const std::string& path) const;
  // `function`, `file` and `line` name the call (filled in by the compiler) for the key
  // observer below.
  void CheckKeys(const Node& map, const std::string& path, const std::vector<std::string>& allowed,
                 const char* function = __builtin_FUNCTION(), const char* file = __builtin_FILE(),
                 int line = __builtin_LINE()) const;
  // A map of named entries: names must be plain identifiers and unique.
  void CheckNames(const Node& map, const std::string& path, const std::string& entity) const;
  const Node& Require(const Node& map, const std::string& path, const std::string& key) const;

  double Number(const Node& node, const std::string& path) const;
  double PositiveNumber(const Node& node, const std::string& path) const;
  double NonNegativeNumber(const Node& node, const std::string& path) const;
  int Integer(const Node& node, const std::string& path, int min, int max) const;
  bool Bool(const Node& node, const std::string& path) const;
  std::string Text(const Node& node, const std::string& path) const;
  // One of `choices`; reports the closest one otherwise.
  std::string Choice(const Node& node, const std::string& path,
                     const std::vector<std::string>& choices) const;
  // A value of an enum with a vocabulary (model/enum_names.h), by its name.
  template <class E>
  E Enum(const Node& node, const std::string& path) const {
    return *EnumFromName<E>(Choice(node, path, EnumNameList<E>()));
  }
  std::vector<double> Numbers(const Node& node, const std::string& path) const;
  // Exactly n numbers.
  std::vector<double> FixedNumbers(const Node& node, const std::string& path, std::size_t n) const;
  Vec3 Vector3(const Node& node, const std::string& path) const;
  Vec6 Vector6(const Node& node, const std::string& path) const;

  // The parameters every number read from now on may name (nullptr: none). Not owned.
  void SetParameters(const ParameterTable* parameters) { parameters_ = parameters; }

 private:
  std::string source_;
  const ParameterTable* parameters_ = nullptr;
};

// The scene reference test (tests/io/scene_reference_test.cpp) holds docs/scene-format.md and
// the reader together: it reads scenes with an observer installed, which sees every map the
// reader checks, with the keys it allows there, so the keys the reader accepts have one source
// of truth, the lists at the CheckKeys calls. Not for use outside that test (not thread-safe).
struct KeyCheck {
  std::string path;                         // dotted path of the map ("" for the top level)
  const std::vector<std::string>* allowed;  // the keys allowed there
  const char* function;                     // the reader function that checked it
  const char* file;                         // the file of the call (as the compiler names it)
  int line;                                 // and the line of the call
};
using KeyCheckObserver = void (*)(const KeyCheck& check, void* context);
void SetKeyCheckObserver(KeyCheckObserver observer, void* context);

// Evaluates a number written as a decimal literal or a small arithmetic expression
// (+ - * / and powers ^ or ** (right-associative, binding tighter than a sign: -2^2 = -4),
// parentheses, the constants pi and deg = pi/180, the functions sqrt sin cos tan asin acos atan
// atan2 exp log, and the names of `parameters`, when given).
// Returns false (and an explanation) when the text is not such an expression.
bool EvaluateExpression(const std::string& text, double* value, std::string* error,
                        const ParameterTable* parameters = nullptr);
// True for the names an expression gives a meaning of its own (pi, deg, the functions): no
// parameter may take them.
bool IsReservedExpressionName(const std::string& name);

}  // namespace screwfem::scene_yaml
