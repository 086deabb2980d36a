// The one way a module declares its configuration keys.
//
// Every module has one options struct (e.g. map::MapOptions) with default member initialisers
// and a `void bind(OptionBinder& b)` that names each key once, with its unit and valid range:
//
//   void bind(OptionBinder& b) {
//     b.real("voxel_size_m", voxel_size_m, 0.001, 1.0, "m", "background voxel edge length");
//   }
//
// Binders implement loading from YAML (with unknown-key detection), range validation, key
// listing (for `emf config`) and the test that conf/default.yaml documents every key.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace emf {

/// The key text of each value of an enum option, e.g. {{Association::kEm, "em"}, ...}.
template <typename E>
using ChoiceNames = std::vector<std::pair<E, const char*>>;

/// The key text of `value` ("?" if `names` lacks it): for messages and run.json.
template <typename E>
const char* choiceName(E value, const ChoiceNames<E>& names) {
  for (const auto& [v, name] : names) {
    if (v == value) return name;
  }
  return "?";
}

class OptionBinder {
 public:
  virtual ~OptionBinder() = default;
  /// A floating-point key with an inclusive valid range [lo, hi].
  virtual void real(const char* key, double& value, double lo, double hi, const char* unit,
                    const char* doc) = 0;
  /// An integer key with an inclusive valid range [lo, hi].
  virtual void integer(const char* key, int& value, int lo, int hi, const char* unit,
                       const char* doc) = 0;
  virtual void boolean(const char* key, bool& value, const char* doc) = 0;
  /// A free-form string (paths, substrings, plugin configs).
  virtual void text(const char* key, std::string& value, const char* doc) = 0;
  /// A string restricted to one of `choices`.
  virtual void choice(const char* key, std::string& value, const std::vector<std::string>& choices,
                      const char* doc) = 0;
  /// A list of strings (YAML sequence).
  virtual void textList(const char* key, std::vector<std::string>& value, const char* doc) = 0;

  /// A choice stored as an enum: read and listed as the key texts of `names`, compared as enums.
  template <typename E>
  void choice(const char* key, E& value, const ChoiceNames<E>& names, const char* doc) {
    std::string text = choiceName(value, names);
    std::vector<std::string> texts;
    for (const auto& entry : names) texts.push_back(entry.second);
    choice(key, text, texts, doc);
    for (const auto& [v, name] : names) {
      if (text == name) value = v;
    }
  }

  /// Convenience for float members (stored and validated as double).
  void realf(const char* key, float& value, double lo, double hi, const char* unit,
             const char* doc) {
    double d = value;
    real(key, d, lo, hi, unit, doc);
    value = static_cast<float>(d);
  }
};

}  // namespace emf
