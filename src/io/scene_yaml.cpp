#include "scene_yaml.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/exceptions.h>
#include <yaml-cpp/mark.h>
#include <yaml-cpp/parser.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <map>
#include <numbers>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include "screwfem/model/errors.h"

namespace screwfem::scene_yaml {

namespace {

// Limits that keep hostile input from exhausting memory or time (docs/scene-format.md,
// "Limits").
constexpr long kMaxNodes = 1000000;          // after alias expansion
constexpr std::size_t kMaxDepth = 100;       // nesting of lists and maps
constexpr std::size_t kMaxExpression = 400;  // characters of one numeric expression

Location FromMark(const YAML::Mark& mark) {
  Location l;
  l.line = mark.line + 1;  // yaml-cpp marks are 0-based
  l.column = mark.column + 1;
  return l;
}

// Builds the tree from parser events. The first error stops the parse (TreeBuilder::Stop is
// thrown through yaml-cpp and caught by Parse), so nothing is built or copied after it.
// Every node is counted once as it is added, an alias by the size of the anchored subtree
// (kept with the anchor), so expansion stops at kMaxNodes after O(kMaxNodes) work; the
// anchors' own copies are bounded the same way.
class TreeBuilder : public YAML::EventHandler {
 public:
  struct Stop {};
  struct Frame {
    Node node;
    YAML::anchor_t anchor = 0;
    bool has_key = false;
    MapEntry key;
    long size = 1;  // nodes in the subtree so far
  };

  std::vector<Node> documents;
  std::string error;
  Location error_location;

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}

  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    Node n;
    n.location = FromMark(mark);
    Add(std::move(n), anchor, 1);
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const auto it = anchors_.find(anchor);
    if (it == anchors_.end()) SetError(FromMark(mark), "alias to an unknown or unfinished anchor");
    const long size = it->second.second;
    if (count_ + size > kMaxNodes)
      SetError(FromMark(mark), "the document expands to more than " + std::to_string(kMaxNodes) +
                                   " nodes (aliases?)");
    Node copy = it->second.first;
    Add(std::move(copy), 0, size);
  }
  void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                const std::string& value) override {
    Node n;
    n.location = FromMark(mark);
    const bool plain = tag == "?";
    if (plain &&
        (value.empty() || value == "~" || value == "null" || value == "Null" || value == "NULL")) {
      n.kind = Node::Kind::kNull;
    } else {
      n.kind = Node::Kind::kScalar;
      n.scalar = value;
      n.quoted = !plain;
    }
    Add(std::move(n), anchor, 1);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    Open(Node::Kind::kSequence, mark, anchor);
  }
  void OnSequenceEnd() override { Close(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    Open(Node::Kind::kMap, mark, anchor);
  }
  void OnMapEnd() override { Close(); }

 private:
  [[noreturn]] void SetError(const Location& at, const std::string& what) {
    error = what;
    error_location = at;
    throw Stop{};
  }
  void Open(Node::Kind kind, const YAML::Mark& mark, YAML::anchor_t anchor) {
    if (stack_.size() >= kMaxDepth)
      SetError(FromMark(mark),
               "lists and maps nested more than " + std::to_string(kMaxDepth) + " levels deep");
    Frame f;
    f.node.kind = kind;
    f.node.location = FromMark(mark);
    f.anchor = anchor;
    stack_.push_back(std::move(f));
  }
  void Close() {
    if (stack_.empty()) return;
    Frame f = std::move(stack_.back());
    stack_.pop_back();
    // The container itself counts one node (its children were counted as they came).
    Add(std::move(f.node), f.anchor, f.size, 1);
  }
  // Adds a node whose subtree has `size` nodes, of which `new_nodes` are not counted yet.
  void Add(Node n, YAML::anchor_t anchor, long size) { Add(std::move(n), anchor, size, size); }
  void Add(Node n, YAML::anchor_t anchor, long size, long new_nodes) {
    count_ += new_nodes;
    if (count_ > kMaxNodes)
      SetError(n.location, "the document has more than " + std::to_string(kMaxNodes) + " nodes");
    if (anchor != 0) {
      anchor_copies_ += size;
      if (anchor_copies_ > kMaxNodes)
        SetError(n.location,
                 "the document's anchors hold more than " + std::to_string(kMaxNodes) + " nodes");
      anchors_[anchor] = {n, size};
    }
    if (stack_.empty()) {
      documents.push_back(std::move(n));
      return;
    }
    Frame& top = stack_.back();
    top.size += size;
    if (top.node.kind == Node::Kind::kSequence) {
      top.node.items.push_back(std::move(n));
      return;
    }
    if (!top.has_key) {
      top.has_key = true;
      top.key.key_location = n.location;
      if (n.kind == Node::Kind::kScalar) {
        top.key.key = n.scalar;
      } else if (n.kind == Node::Kind::kNull) {
        SetError(n.location, "empty map key");
      } else {
        SetError(n.location, "map keys must be plain names, not lists or maps");
      }
      return;
    }
    top.has_key = false;
    // An empty value gets its key's location (yaml-cpp marks it at the next token).
    if (n.kind == Node::Kind::kNull) n.location = top.key.key_location;
    top.node.entries.emplace_back(std::move(top.key), std::move(n));
    top.key = MapEntry{};
  }

  std::vector<Frame> stack_;
  std::map<YAML::anchor_t, std::pair<Node, long>> anchors_;  // node and its subtree size
  long count_ = 0;
  long anchor_copies_ = 0;
};

// Binary content: NUL and other control bytes, or invalid UTF-8. Returns the byte offset of the
// first offending byte, or npos.
std::size_t FindBinary(const std::string& text) {
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t n = text.size();
  std::size_t i = 0;
  while (i < n) {
    const unsigned char c = s[i];
    if (c < 0x80) {
      if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7f) return i;
      ++i;
      continue;
    }
    int len = 0;
    if ((c & 0xE0) == 0xC0 && c >= 0xC2)
      len = 2;
    else if ((c & 0xF0) == 0xE0)
      len = 3;
    else if ((c & 0xF8) == 0xF0 && c <= 0xF4)
      len = 4;
    else
      return i;
    if (i + static_cast<std::size_t>(len) > n) return i;
    for (int k = 1; k < len; ++k)
      if ((s[i + static_cast<std::size_t>(k)] & 0xC0) != 0x80) return i;
    i += static_cast<std::size_t>(len);
  }
  return std::string::npos;
}

Location LocationOfOffset(const std::string& text, std::size_t offset) {
  Location l;
  l.line = 1;
  l.column = 1;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++l.line;
      l.column = 1;
    } else {
      ++l.column;
    }
  }
  return l;
}

void MarkOverride(Node& n, const std::shared_ptr<const std::string>& text) {
  n.location = Location{};
  n.location.override_text = text;
  for (Node& item : n.items) MarkOverride(item, text);
  for (auto& entry : n.entries) {
    entry.first.key_location = n.location;
    MarkOverride(entry.second, text);
  }
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// --- numeric expressions -----------------------------------------------------------------------
class ExpressionParser {
 public:
  ExpressionParser(const std::string& text, const ParameterTable* parameters)
      : s_(text), parameters_(parameters) {}

  bool Run(double* value, std::string* error) {
    double v = 0.0;
    if (!Expr(&v)) {
      *error = error_;
      return false;
    }
    SkipSpace();
    if (pos_ != s_.size()) {
      *error = "unexpected '" + s_.substr(pos_, 1) + "'";
      return false;
    }
    *value = v;
    return true;
  }

 private:
  void SkipSpace() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t')) ++pos_;
  }
  bool Fail(const std::string& what) {
    if (error_.empty()) error_ = what;
    return false;
  }
  bool Expr(double* v) {
    if (!Term(v)) return false;
    for (;;) {
      SkipSpace();
      if (pos_ >= s_.size() || (s_[pos_] != '+' && s_[pos_] != '-')) return true;
      const char op = s_[pos_++];
      double rhs = 0.0;
      if (!Term(&rhs)) return false;
      *v = op == '+' ? *v + rhs : *v - rhs;
    }
  }
  bool Term(double* v) {
    if (!Unary(v)) return false;
    for (;;) {
      SkipSpace();
      if (pos_ >= s_.size() || (s_[pos_] != '*' && s_[pos_] != '/')) return true;
      const char op = s_[pos_++];
      double rhs = 0.0;
      if (!Unary(&rhs)) return false;
      *v = op == '*' ? *v * rhs : *v / rhs;
    }
  }
  bool Unary(double* v) {
    SkipSpace();
    if (++depth_ > 64) return Fail("expression nested too deeply");
    bool ok = false;
    if (pos_ < s_.size() && (s_[pos_] == '-' || s_[pos_] == '+')) {
      const char op = s_[pos_++];
      ok = Unary(v);
      if (ok && op == '-') *v = -*v;
    } else {
      ok = Power(v);
    }
    --depth_;
    return ok;
  }
  // primary [(^ | **) unary]: right-associative (2^3^2 = 2^9), the exponent may carry a sign.
  bool Power(double* v) {
    if (!Primary(v)) return false;
    SkipSpace();
    std::size_t op = 0;
    if (pos_ < s_.size() && s_[pos_] == '^') op = 1;
    if (pos_ + 1 < s_.size() && s_[pos_] == '*' && s_[pos_ + 1] == '*') op = 2;
    if (op == 0) return true;
    pos_ += op;
    double exponent = 0.0;
    if (!Unary(&exponent)) return false;
    *v = std::pow(*v, exponent);
    return true;
  }
  bool Primary(double* v) {
    SkipSpace();
    if (pos_ >= s_.size()) return Fail("unexpected end");
    const char c = s_[pos_];
    if (c == '(') {
      ++pos_;
      if (!Expr(v)) return false;
      SkipSpace();
      if (pos_ >= s_.size() || s_[pos_] != ')') return Fail("missing ')'");
      ++pos_;
      return true;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return NumberLiteral(v);
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      const std::size_t start = pos_;
      while (pos_ < s_.size() &&
             (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
        ++pos_;
      const std::string name = s_.substr(start, pos_ - start);
      if (name == "pi") {
        *v = std::numbers::pi;
        return true;
      }
      if (name == "deg") {
        *v = std::numbers::pi / 180.0;
        return true;
      }
      SkipSpace();
      if (pos_ >= s_.size() || s_[pos_] != '(') return Name(name, v);
      ++pos_;
      std::vector<double> args;
      for (;;) {
        double a = 0.0;
        if (!Expr(&a)) return false;
        args.push_back(a);
        SkipSpace();
        if (pos_ < s_.size() && s_[pos_] == ',') {
          ++pos_;
          continue;
        }
        if (pos_ < s_.size() && s_[pos_] == ')') {
          ++pos_;
          break;
        }
        return Fail("missing ')'");
      }
      return Call(name, args, v);
    }
    return Fail("unexpected '" + s_.substr(pos_, 1) + "'");
  }
  // A parameter's value.
  bool Name(const std::string& name, double* v) {
    std::vector<std::string> known = {"pi", "deg"};
    if (parameters_ != nullptr) {
      for (const auto& [key, value] : *parameters_) {
        if (key == name) {
          *v = value;
          return true;
        }
      }
      for (const auto& entry : *parameters_) known.push_back(entry.first);
    }
    return Fail("unknown name '" + name + "'" + UnknownNameHint(name, known));
  }
  bool Call(const std::string& name, const std::vector<double>& a, double* v) {
    using F = double (*)(double);
    static const std::map<std::string, F> unary = {
        {"sqrt", [](double x) { return std::sqrt(x); }},
        {"sin", [](double x) { return std::sin(x); }},
        {"cos", [](double x) { return std::cos(x); }},
        {"tan", [](double x) { return std::tan(x); }},
        {"asin", [](double x) { return std::asin(x); }},
        {"acos", [](double x) { return std::acos(x); }},
        {"atan", [](double x) { return std::atan(x); }},
        {"exp", [](double x) { return std::exp(x); }},
        {"log", [](double x) { return std::log(x); }},
    };
    if (name == "atan2") {
      if (a.size() != 2) return Fail("atan2 takes two arguments");
      *v = std::atan2(a[0], a[1]);
      return true;
    }
    const auto it = unary.find(name);
    if (it == unary.end()) return Fail("unknown function '" + name + "'");
    if (a.size() != 1) return Fail(name + " takes one argument");
    *v = it->second(a[0]);
    return true;
  }
  bool NumberLiteral(double* v) {
    const std::size_t start = pos_;
    while (pos_ < s_.size() &&
           (std::isdigit(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '.'))
      ++pos_;
    if (pos_ < s_.size() && (s_[pos_] == 'e' || s_[pos_] == 'E')) {
      std::size_t p = pos_ + 1;
      if (p < s_.size() && (s_[p] == '+' || s_[p] == '-')) ++p;
      if (p < s_.size() && std::isdigit(static_cast<unsigned char>(s_[p]))) {
        pos_ = p;
        while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) ++pos_;
      }
    }
    const char* first = s_.data() + start;
    const char* last = s_.data() + pos_;
    const auto result = std::from_chars(first, last, *v);
    if (result.ec == std::errc::result_out_of_range) return Fail("number out of range");
    if (result.ec != std::errc() || result.ptr != last)
      return Fail("malformed number '" + s_.substr(start, pos_ - start) + "'");
    return true;
  }

  const std::string& s_;
  const ParameterTable* parameters_;
  std::size_t pos_ = 0;
  int depth_ = 0;
  std::string error_;
};

std::string Quote(const std::string& s) {
  std::string shown = s.size() > 60 ? s.substr(0, 57) + "..." : s;
  return "'" + shown + "'";
}

}  // namespace

// ---------------------------------------------------------------------------------------------
const Node* Node::Find(const std::string& key) const {
  for (const auto& entry : entries)
    if (entry.first.key == key) return &entry.second;
  return nullptr;
}
Node* Node::Find(const std::string& key) {
  for (auto& entry : entries)
    if (entry.first.key == key) return &entry.second;
  return nullptr;
}
const MapEntry* Node::FindEntry(const std::string& key) const {
  for (const auto& entry : entries)
    if (entry.first.key == key) return &entry.first;
  return nullptr;
}

std::string Where(const std::string& source, const Location& location) {
  if (location.override_text) return source + ": override '" + *location.override_text + "'";
  if (location.line <= 0) return source;
  return source + ":" + std::to_string(location.line) + ":" + std::to_string(location.column);
}

std::string Describe(const Node& node) {
  switch (node.kind) {
    case Node::Kind::kNull:
      return "nothing";
    case Node::Kind::kScalar:
      return Quote(node.scalar);
    case Node::Kind::kSequence:
      return "a list";
    case Node::Kind::kMap:
      return "a map";
  }
  return "?";
}

Node Parse(const std::string& text, const std::string& source, bool allow_empty) {
  const std::size_t bad = FindBinary(text);
  if (bad != std::string::npos) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02x",
                  static_cast<unsigned>(static_cast<unsigned char>(text[bad])));
    throw InputError(Where(source, LocationOfOffset(text, bad)) + ": not a YAML text file (byte " +
                     hex + " is not text)");
  }
  TreeBuilder builder;
  std::istringstream in(text);
  int documents = 0;
  try {
    YAML::Parser parser(in);
    while (parser.HandleNextDocument(builder)) {
      if (++documents > 1) break;
    }
  } catch (const TreeBuilder::Stop&) {
    // builder.error says why
  } catch (const YAML::Exception& e) {
    throw InputError(Where(source, FromMark(e.mark)) + ": not valid YAML: " + e.msg);
  }
  if (!builder.error.empty())
    throw InputError(Where(source, builder.error_location) + ": " + builder.error);
  if (builder.documents.size() > 1)
    throw InputError(Where(source, builder.documents[1].location) +
                     ": a scene file holds one YAML document, found a second one");
  if (builder.documents.empty() || builder.documents[0].IsNull()) {
    if (allow_empty) return Node{};
    Location start;
    start.line = 1;
    start.column = 1;
    throw InputError(Where(source, start) + ": empty scene (no YAML content)");
  }
  return std::move(builder.documents[0]);
}

namespace {

// The components of an override's key path as [begin, end) offsets into `path` (the dotted
// prefix up to a component is a prefix of `path`: no per-component copies).
std::vector<std::pair<std::size_t, std::size_t>> SplitKeyPath(const std::string& path,
                                                              const std::string& where) {
  std::vector<std::pair<std::size_t, std::size_t>> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t dot = path.find('.', start);
    const std::size_t end = dot == std::string::npos ? path.size() : dot;
    if (end == start || path.find_first_of(" \t", start) < end)
      throw InputError(where + ": malformed key path '" + path + "'");
    parts.emplace_back(start, end);
    if (parts.size() > kMaxOverrideDepth)
      throw InputError(where + ": the key path has more than " + std::to_string(kMaxOverrideDepth) +
                       " components");
    if (dot == std::string::npos) return parts;
    start = dot + 1;
  }
}

// One step of an override's key path from `cur` (whose dotted path is `cur_path`) to its
// component `part`: a list index, or a map key (created unless `cur` is a named collection and
// the step is not the last).
Node* Descend(Node* cur, const std::string& part, std::string_view cur_path, bool last,
              const std::shared_ptr<const std::string>& text, const std::string& where,
              const std::vector<std::string>& collections) {
  if (cur->IsNull()) cur->kind = Node::Kind::kMap;  // descend into an empty value
  if (cur->IsSequence()) {
    std::size_t index = 0;
    const auto r = std::from_chars(part.data(), part.data() + part.size(), index);
    if (r.ec != std::errc() || r.ptr != part.data() + part.size() || index >= cur->items.size())
      throw InputError(where + ": '" + std::string(cur_path) + "' is a list of " +
                       std::to_string(cur->items.size()) + " items; '" + part +
                       "' is not an index into it");
    return &cur->items[index];
  }
  if (!cur->IsMap())
    throw InputError(where + ": '" + std::string(cur_path) + "' is a single value, it has no '" +
                     part + "'");
  if (Node* next = cur->Find(part)) return next;
  const bool in_collection =
      std::find(collections.begin(), collections.end(), cur_path) != collections.end();
  if (in_collection && !last) {
    std::vector<std::string> names;
    for (const auto& e : cur->entries) names.push_back(e.first.key);
    throw InputError(where + ": " + std::string(cur_path) + ": no entry '" + part + "'" +
                     DidYouMean(part, names));
  }
  MapEntry key;
  key.key = part;
  key.key_location.override_text = text;
  Node created;
  created.location.override_text = text;
  cur->entries.emplace_back(std::move(key), std::move(created));
  return &cur->entries.back().second;
}

// "a.b.c=": removes c from a.b when both are there (the reader then takes c's default).
void RemoveKey(Node& root, const std::string& path,
               const std::vector<std::pair<std::size_t, std::size_t>>& parts,
               const std::string& where) {
  Node* cur = &root;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string part = path.substr(parts[i].first, parts[i].second - parts[i].first);
    if (cur->IsSequence()) {
      if (i + 1 == parts.size())
        throw InputError(where + ": an item of a list cannot be removed (give the whole list)");
      std::size_t index = 0;
      const auto r = std::from_chars(part.data(), part.data() + part.size(), index);
      if (r.ec != std::errc() || r.ptr != part.data() + part.size() || index >= cur->items.size())
        return;  // no such item: nothing to remove
      cur = &cur->items[index];
      continue;
    }
    if (!cur->IsMap()) return;
    if (i + 1 == parts.size()) {
      auto& entries = cur->entries;
      entries.erase(std::remove_if(entries.begin(), entries.end(),
                                   [&](const auto& e) { return e.first.key == part; }),
                    entries.end());
      return;
    }
    cur = cur->Find(part);
    if (cur == nullptr) return;
  }
}

}  // namespace

void ApplyOverride(Node& root, const std::string& override_text, const std::string& source,
                   const std::vector<std::string>& collections) {
  const std::string where = source + ": override '" + override_text + "'";
  const std::size_t eq = override_text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(where + ": expected KEY.PATH=VALUE (e.g. analysis.step=5e-4)");
  const std::string path = override_text.substr(0, eq);
  const std::string value_text = override_text.substr(eq + 1);
  const std::vector<std::pair<std::size_t, std::size_t>> parts = SplitKeyPath(path, where);

  if (value_text.find_first_not_of(" \t") == std::string::npos) {
    RemoveKey(root, path, parts, where);
    return;
  }
  const auto text = std::make_shared<const std::string>(override_text);
  Node value;
  try {
    value = Parse(value_text, "value", /*allow_empty=*/true);
  } catch (const InputError& e) {
    throw InputError(where + ": the value is not a YAML value (" + e.what() + ")");
  }
  MarkOverride(value, text);
  if (root.IsNull()) root.kind = Node::Kind::kMap;
  if (!root.IsMap()) throw InputError(where + ": the scene is not a map");

  Node* cur = &root;
  std::size_t cur_end = 0;  // cur's dotted path is path.substr(0, cur_end)
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string part = path.substr(parts[i].first, parts[i].second - parts[i].first);
    cur = Descend(cur, part, std::string_view(path.data(), cur_end), i + 1 == parts.size(), text,
                  where, collections);
    cur_end = parts[i].second;
  }
  *cur = std::move(value);
}

std::string Closest(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string w = Lower(word);
  std::string best;
  std::size_t best_d = std::string::npos;
  for (const std::string& c : candidates) {
    const std::size_t d = EditDistance(w, Lower(c));
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  const std::size_t limit = w.size() <= 3 ? 1 : w.size() <= 6 ? 2 : 3;
  if (best_d == std::string::npos || best_d > limit || best_d >= w.size()) return "";
  return best;
}

std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string c = Closest(word, candidates);
  return c.empty() ? "" : " (did you mean '" + c + "'?)";
}

std::string UnknownNameHint(const std::string& word, const std::vector<std::string>& candidates) {
  std::string hint = DidYouMean(word, candidates);
  if (!hint.empty() || candidates.empty()) return hint;
  hint = " (known: ";
  for (std::size_t i = 0; i < candidates.size() && i < 8; ++i)
    hint += (i ? ", " : "") + candidates[i];
  return hint + (candidates.size() > 8 ? ", ...)" : ")");
}

bool EvaluateExpression(const std::string& text, double* value, std::string* error,
                        const ParameterTable* parameters) {
  if (text.size() > kMaxExpression) {
    *error = "expression too long";
    return false;
  }
  ExpressionParser p(text, parameters);
  return p.Run(value, error);
}

bool IsReservedExpressionName(const std::string& name) {
  static const char* const kReserved[] = {"pi",   "deg",  "sqrt", "sin", "cos",   "tan",
                                          "asin", "acos", "atan", "exp", "atan2", "log"};
  return std::any_of(std::begin(kReserved), std::end(kReserved),
                     [&](const char* r) { return name == r; });
}

// ---------------------------------------------------------------------------------------------
void Reader::Fail(const Location& at, const std::string& path, const std::string& what) const {
  throw InputError(Where(source_, at) + ": " + (path.empty() ? "" : path + ": ") + what);
}

void Reader::ExpectMap(const Node& node, const std::string& path) const {
  if (!node.IsMap())
    Fail(node.location, path, "expected a map (key: value entries), got " + Describe(node));
}

namespace {
KeyCheckObserver key_check_observer = nullptr;
void* key_check_context = nullptr;
}  // namespace

void SetKeyCheckObserver(KeyCheckObserver observer, void* context) {
  key_check_observer = observer;
  key_check_context = context;
}

void Reader::CheckKeys(const Node& map, const std::string& path,
                       const std::vector<std::string>& allowed, const char* function,
                       const char* file, int line) const {
  if (key_check_observer != nullptr)
    key_check_observer(KeyCheck{path, &allowed, function, file, line}, key_check_context);
  ExpectMap(map, path);
  std::unordered_map<std::string_view, std::size_t> first;  // key -> its first entry
  for (std::size_t i = 0; i < map.entries.size(); ++i) {
    const MapEntry& e = map.entries[i].first;
    if (std::find(allowed.begin(), allowed.end(), e.key) == allowed.end())
      Fail(e.key_location, path.empty() ? e.key : path + "." + e.key,
           "unknown key '" + e.key + "'" + DidYouMean(e.key, allowed));
    const auto [it, fresh] = first.emplace(e.key, i);
    if (!fresh)
      Fail(e.key_location, path.empty() ? e.key : path + "." + e.key,
           "duplicate key '" + e.key + "' (first given at " +
               Where(source_, map.entries[it->second].first.key_location) + ")");
  }
}

void Reader::CheckNames(const Node& map, const std::string& path, const std::string& entity) const {
  ExpectMap(map, path);
  // Names seen, each with its first entry: linear in the entries (a pairwise search took
  // seconds for 1e5 names).
  std::unordered_map<std::string_view, std::size_t> first;
  for (std::size_t i = 0; i < map.entries.size(); ++i) {
    const MapEntry& e = map.entries[i].first;
    const bool ok = !e.key.empty() && std::all_of(e.key.begin(), e.key.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
    });
    if (!ok)
      Fail(e.key_location, path + "." + e.key,
           "a " + entity + " name may only contain letters, digits, '_' and '-'");
    const auto [it, fresh] = first.emplace(e.key, i);
    if (!fresh)
      Fail(e.key_location, path + "." + e.key,
           "duplicate " + entity + " name '" + e.key + "' (first defined at " +
               Where(source_, map.entries[it->second].first.key_location) + ")");
  }
}

const Node& Reader::Require(const Node& map, const std::string& path,
                            const std::string& key) const {
  const Node* n = map.Find(key);
  if (n == nullptr) Fail(map.location, path, "missing key '" + key + "'");
  return *n;
}

double Reader::Number(const Node& node, const std::string& path) const {
  if (!node.IsScalar()) Fail(node.location, path, "expected a number, got " + Describe(node));
  double v = 0.0;
  std::string error;
  if (!EvaluateExpression(node.scalar, &v, &error, parameters_))
    Fail(node.location, path, "expected a number, got " + Quote(node.scalar) + " (" + error + ")");
  if (!std::isfinite(v))
    Fail(node.location, path, "expected a finite number, got " + Quote(node.scalar));
  return v;
}

double Reader::PositiveNumber(const Node& node, const std::string& path) const {
  const double v = Number(node, path);
  if (!(v > 0.0))
    Fail(node.location, path, "expected a positive number, got " + Quote(node.scalar));
  return v;
}

double Reader::NonNegativeNumber(const Node& node, const std::string& path) const {
  const double v = Number(node, path);
  if (!(v >= 0.0))
    Fail(node.location, path, "expected a non-negative number, got " + Quote(node.scalar));
  return v;
}

int Reader::Integer(const Node& node, const std::string& path, int min, int max) const {
  if (!node.IsScalar()) Fail(node.location, path, "expected an integer, got " + Describe(node));
  double v = 0.0;
  std::string error;
  if (!EvaluateExpression(node.scalar, &v, &error, parameters_))
    Fail(node.location, path,
         "expected an integer, got " + Quote(node.scalar) + " (" + error + ")");
  if (!std::isfinite(v) || v != std::floor(v))
    Fail(node.location, path, "expected an integer, got " + Quote(node.scalar));
  if (v < min || v > max)
    Fail(node.location, path,
         "expected an integer from " + std::to_string(min) + " to " + std::to_string(max) +
             ", got " + Quote(node.scalar));
  return static_cast<int>(v);
}

bool Reader::Bool(const Node& node, const std::string& path) const {
  if (node.IsScalar()) {
    const std::string s = Lower(node.scalar);
    if (s == "true") return true;
    if (s == "false") return false;
  }
  Fail(node.location, path, "expected true or false, got " + Describe(node));
}

std::string Reader::Text(const Node& node, const std::string& path) const {
  if (!node.IsScalar() || node.scalar.empty())
    Fail(node.location, path, "expected a name or text, got " + Describe(node));
  return node.scalar;
}

std::string Reader::Choice(const Node& node, const std::string& path,
                           const std::vector<std::string>& choices) const {
  std::string all;
  for (std::size_t i = 0; i < choices.size(); ++i)
    all += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i];
  if (!node.IsScalar())
    Fail(node.location, path, "expected one of " + all + ", got " + Describe(node));
  if (std::find(choices.begin(), choices.end(), node.scalar) == choices.end())
    Fail(node.location, path,
         "expected one of " + all + ", got " + Quote(node.scalar) +
             DidYouMean(node.scalar, choices));
  return node.scalar;
}

std::vector<double> Reader::Numbers(const Node& node, const std::string& path) const {
  if (!node.IsSequence())
    Fail(node.location, path, "expected a list of numbers, got " + Describe(node));
  std::vector<double> v;
  v.reserve(node.items.size());
  for (std::size_t i = 0; i < node.items.size(); ++i)
    v.push_back(Number(node.items[i], path + "[" + std::to_string(i) + "]"));
  return v;
}

std::vector<double> Reader::FixedNumbers(const Node& node, const std::string& path,
                                         std::size_t n) const {
  if (!node.IsSequence() || node.items.size() != n)
    Fail(node.location, path,
         "expected a list of " + std::to_string(n) + " numbers, got " +
             (node.IsSequence() ? "a list of " + std::to_string(node.items.size())
                                : Describe(node)));
  return Numbers(node, path);
}

Vec3 Reader::Vector3(const Node& node, const std::string& path) const {
  const std::vector<double> v = FixedNumbers(node, path, 3);
  return Vec3(v[0], v[1], v[2]);
}

Vec6 Reader::Vector6(const Node& node, const std::string& path) const {
  const std::vector<double> v = FixedNumbers(node, path, 6);
  Vec6 r;
  for (int i = 0; i < 6; ++i) r(i) = v[static_cast<std::size_t>(i)];
  return r;
}

}  // namespace screwfem::scene_yaml
