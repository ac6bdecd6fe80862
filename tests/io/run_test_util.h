// Readers for the files a run writes (run.h), shared by run_test.cpp and cli_test.cpp: a CSV
// table reader that checks every line is complete, and a strict little JSON parser.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace screwfem::test {

// Linked with AddressSanitizer (the sanitizer build defines SCREWFEM_SANITIZED for the test
// programs, which it does not instrument; an instrumented build: GCC defines
// __SANITIZE_ADDRESS__, Clang answers __has_feature): tests that limit the address space skip,
// ASan reserves more than the limit.
#if defined(SCREWFEM_SANITIZED) || defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A new empty directory of its own for one test (under the system's temporary directory).
inline std::string FreshDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("screwfem_run_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

// A fresh directory removed at the end of its scope unless the test failed (kept to look at).
class ScopedDir {
 public:
  explicit ScopedDir(const std::string& name) : path_(FreshDir(name)) {}
  ScopedDir(const ScopedDir&) = delete;
  ScopedDir& operator=(const ScopedDir&) = delete;
  ~ScopedDir() {
    std::error_code ec;
    if (!::testing::Test::HasFailure()) std::filesystem::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  bool well_formed = false;  // ends with a newline; every row has one value per column
  std::string problem;
  int Column(const std::string& name) const {
    for (std::size_t i = 0; i < columns.size(); ++i)
      if (columns[i] == name) return static_cast<int>(i);
    return -1;
  }
};

inline Table ReadCsv(const std::string& path) {
  Table t;
  const std::string text = ReadFile(path);
  if (text.empty() || text.back() != '\n') {
    t.problem = "missing or not ending with a newline";
    return t;
  }
  std::stringstream lines(text);
  std::string line;
  bool header = true;
  while (std::getline(lines, line)) {
    std::vector<std::string> fields;
    std::stringstream f(line);
    std::string field;
    while (std::getline(f, field, ',')) fields.push_back(field);
    if (header) {
      t.columns = fields;
      header = false;
      continue;
    }
    if (fields.size() != t.columns.size()) {
      t.problem = "row " + std::to_string(t.rows.size()) + " has " + std::to_string(fields.size()) +
                  " fields";
      return t;
    }
    std::vector<double> row;
    for (const std::string& s : fields) {
      char* end = nullptr;
      row.push_back(std::strtod(s.c_str(), &end));
      if (end == s.c_str() || *end != '\0') {
        t.problem = "not a number: '" + s + "'";
        return t;
      }
    }
    t.rows.push_back(std::move(row));
  }
  t.well_formed = true;
  return t;
}

// A JSON value (RFC 8259 subset the summary needs; the parser rejects anything else).
struct Json {
  enum class Kind { kNull, kBool, kNumber, kString, kArray, kObject } kind = Kind::kNull;
  bool boolean = false;
  double number = 0.0;
  std::string string;
  std::vector<Json> array;
  std::map<std::string, Json> object;

  // Member lookup by a dotted path ("counts.nodes"); nullptr when absent.
  const Json* Find(const std::string& path) const {
    const Json* v = this;
    std::stringstream s(path);
    std::string key;
    while (std::getline(s, key, '.')) {
      if (v->kind != Kind::kObject) return nullptr;
      const auto it = v->object.find(key);
      if (it == v->object.end()) return nullptr;
      v = &it->second;
    }
    return v;
  }
};

class JsonParser {
 public:
  explicit JsonParser(const std::string& text) : s_(text) {}
  std::optional<Json> Parse() {
    Json v;
    if (!Value(&v)) return std::nullopt;
    Space();
    if (i_ != s_.size()) return std::nullopt;
    return v;
  }

 private:
  void Space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool Literal(const char* word) {
    const std::string w(word);
    if (s_.compare(i_, w.size(), w) != 0) return false;
    i_ += w.size();
    return true;
  }
  bool String(std::string* out) {
    if (s_[i_] != '"') return false;
    ++i_;
    while (i_ < s_.size()) {
      const char c = s_[i_++];
      if (c == '"') return true;
      if (static_cast<unsigned char>(c) < 0x20) return false;  // raw control characters
      if (c != '\\') {
        *out += c;
        continue;
      }
      if (i_ >= s_.size()) return false;
      const char e = s_[i_++];
      switch (e) {
        case '"':
          *out += '"';
          break;
        case '\\':
          *out += '\\';
          break;
        case '/':
          *out += '/';
          break;
        case 'n':
          *out += '\n';
          break;
        case 'r':
          *out += '\r';
          break;
        case 't':
          *out += '\t';
          break;
        case 'b':
          *out += '\b';
          break;
        case 'f':
          *out += '\f';
          break;
        case 'u': {
          if (i_ + 4 > s_.size()) return false;
          const long code = std::strtol(s_.substr(i_, 4).c_str(), nullptr, 16);
          i_ += 4;
          if (code >= 0x80) return false;  // the summary escapes only ASCII control characters
          *out += static_cast<char>(code);
          break;
        }
        default:
          return false;
      }
    }
    return false;
  }
  bool Value(Json* v) {
    Space();
    if (i_ >= s_.size()) return false;
    const char c = s_[i_];
    if (c == '{') {
      v->kind = Json::Kind::kObject;
      ++i_;
      Space();
      if (i_ < s_.size() && s_[i_] == '}') return ++i_, true;
      while (true) {
        Space();
        std::string key;
        if (i_ >= s_.size() || !String(&key)) return false;
        Space();
        if (i_ >= s_.size() || s_[i_++] != ':') return false;
        Json member;
        if (!Value(&member) || v->object.count(key)) return false;
        v->object.emplace(key, std::move(member));
        Space();
        if (i_ >= s_.size()) return false;
        if (s_[i_] == '}') return ++i_, true;
        if (s_[i_++] != ',') return false;
      }
    }
    if (c == '[') {
      v->kind = Json::Kind::kArray;
      ++i_;
      Space();
      if (i_ < s_.size() && s_[i_] == ']') return ++i_, true;
      while (true) {
        Json element;
        if (!Value(&element)) return false;
        v->array.push_back(std::move(element));
        Space();
        if (i_ >= s_.size()) return false;
        if (s_[i_] == ']') return ++i_, true;
        if (s_[i_++] != ',') return false;
      }
    }
    if (c == '"') {
      v->kind = Json::Kind::kString;
      return String(&v->string);
    }
    if (Literal("true")) return v->kind = Json::Kind::kBool, v->boolean = true, true;
    if (Literal("false")) return v->kind = Json::Kind::kBool, v->boolean = false, true;
    if (Literal("null")) return v->kind = Json::Kind::kNull, true;
    // Numbers: -?digits(.digits)?([eE][+-]?digits)?
    const std::size_t start = i_;
    if (s_[i_] == '-') ++i_;
    const auto digits = [&] {
      const std::size_t d = i_;
      while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_;
      return i_ > d;
    };
    if (!digits()) return false;
    if (i_ < s_.size() && s_[i_] == '.' && (++i_, !digits())) return false;
    if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
      ++i_;
      if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) ++i_;
      if (!digits()) return false;
    }
    v->kind = Json::Kind::kNumber;
    v->number = std::strtod(s_.substr(start, i_ - start).c_str(), nullptr);
    return true;
  }

  const std::string& s_;
  std::size_t i_ = 0;
};

inline std::optional<Json> ParseJsonFile(const std::string& path) {
  return JsonParser(ReadFile(path)).Parse();
}

}  // namespace screwfem::test
