// One vocabulary per option: the names of an enum's values as scene files, summary.json,
// messages and Python spell them (Python in capitals: NewtonMatrix.SIMPLIFIED), defined once
// beside the enum by a specialisation of EnumNames (docs/architecture.md, "Options"):
//
//   template <> struct EnumNames<NewtonMatrix> {
//     static constexpr std::array<EnumName<NewtonMatrix>, 2> kValues = {{
//         {NewtonMatrix::kSimplified, "simplified", "..."}, {NewtonMatrix::kFull, "full", "..."}}};
//   };
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace screwfem {

template <class E>
struct EnumName {
  E value;
  const char* name;  // lower case, words joined by '_'
  const char* doc;   // one line for help texts and Python docstrings
};

template <class E>
struct EnumNames;  // specialised for each enum with a vocabulary

// The name of a value (nullptr for a value outside the enum, e.g. cast from an integer).
template <class E>
const char* NameOf(E value) {
  for (const EnumName<E>& v : EnumNames<E>::kValues)
    if (v.value == value) return v.name;
  return nullptr;
}
template <class E>
bool IsEnumValue(E value) {
  return NameOf(value) != nullptr;
}
// The value of a name, or nothing.
template <class E>
std::optional<E> EnumFromName(std::string_view name) {
  for (const EnumName<E>& v : EnumNames<E>::kValues)
    if (name == v.name) return v.value;
  return std::nullopt;
}
// Every name, in declaration order.
template <class E>
std::vector<std::string> EnumNameList() {
  std::vector<std::string> names;
  for (const EnumName<E>& v : EnumNames<E>::kValues) names.emplace_back(v.name);
  return names;
}
// "a, b or c" (for messages).
template <class E>
std::string EnumNameAlternatives() {
  std::string s;
  const auto& values = EnumNames<E>::kValues;
  for (std::size_t i = 0; i < values.size(); ++i)
    s += std::string(i == 0 ? "" : i + 1 == values.size() ? " or " : ", ") + values[i].name;
  return s;
}

}  // namespace screwfem
