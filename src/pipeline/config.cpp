#include "pipeline/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "common/error.h"

namespace emf {
namespace {

std::string formatNumber(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  return os.str();
}

std::string rangeText(double lo, double hi) {
  return "[" + formatNumber(lo) + ", " + formatNumber(hi) + "]";
}

std::string joinChoices(const std::vector<std::string>& choices) {
  std::string s;
  for (size_t i = 0; i < choices.size(); ++i) s += (i ? "|" : "") + choices[i];
  return s;
}

std::string lowerCase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string closest(const std::string& key, const std::vector<std::string>& candidates) {
  std::string best;
  int best_d = 1 << 30;
  for (const auto& c : candidates) {
    if (lowerCase(key) == lowerCase(c)) return c;  // only the case differs (keys are lower case)
    const int d = editDistance(key, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  // Only suggest plausible typos: at most half the key's length edited.
  if (best.empty() || best_d > std::max<int>(3, static_cast<int>(key.size()) / 2)) return "";
  return best;
}

/// "--set s.k=v" is parsed as a two-line document made here: its line numbers mean nothing.
bool hasLines(const std::string& origin) { return origin.rfind("--set ", 0) != 0; }

std::string where(const std::string& origin, const YAML::Node& node) {
  const YAML::Mark m = node.Mark();
  if (m.line >= 0 && hasLines(origin)) return origin + ":" + std::to_string(m.line + 1);
  return origin;
}

/// YAML allows a key twice in a mapping and yaml-cpp keeps the first: a later override would be
/// dropped without a word. `prefix` is "" for sections, "<section>." for keys.
void rejectDuplicateKeys(const YAML::Node& mapping, const std::string& origin,
                         const std::string& prefix) {
  if (!mapping || !mapping.IsMap()) return;
  std::map<std::string, YAML::Node> seen;
  for (const auto& kv : mapping) {
    const std::string k = kv.first.Scalar();
    const auto it = seen.find(k);
    if (it != seen.end()) {
      throw ConfigError(where(origin, kv.first) + ": '" + prefix + k +
                        "' is given twice (first at " + where(origin, it->second) + "): keep one");
    }
    seen.emplace(k, kv.first);
  }
}

/// Reads one section of a YAML document into an options struct.
class YamlReadBinder : public OptionBinder {
 public:
  YamlReadBinder(const YAML::Node& section, std::string origin, std::string section_name)
      : section_(section), origin_(std::move(origin)), name_(std::move(section_name)) {}

  void real(const char* key, double& value, double lo, double hi, const char* unit,
            const char*) override {
    const YAML::Node n = take(key);
    if (!n) return;
    double v = 0;
    std::string unit_text = (unit && *unit) ? std::string(" ") + unit : "";
    if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !std::isfinite(v)) {
      fail(n, key, "expected a number in " + rangeText(lo, hi) + unit_text + ", got " + show(n));
    }
    if (v < lo || v > hi) {
      fail(n, key,
           "value " + formatNumber(v) + " is out of range " + rangeText(lo, hi) + unit_text);
    }
    value = v;
  }

  void integer(const char* key, int& value, int lo, int hi, const char* unit,
               const char*) override {
    const YAML::Node n = take(key);
    if (!n) return;
    long long v = 0;
    std::string unit_text = (unit && *unit) ? std::string(" ") + unit : "";
    if (!n.IsScalar() || !YAML::convert<long long>::decode(n, v)) {
      fail(n, key, "expected an integer in " + rangeText(lo, hi) + unit_text + ", got " + show(n));
    }
    if (v < lo || v > hi) {
      fail(n, key,
           "value " + std::to_string(v) + " is out of range " + rangeText(lo, hi) + unit_text);
    }
    value = static_cast<int>(v);
  }

  void boolean(const char* key, bool& value, const char*) override {
    const YAML::Node n = take(key);
    if (!n) return;
    bool v = false;
    if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) {
      fail(n, key, "expected true or false, got " + show(n));
    }
    value = v;
  }

  void text(const char* key, std::string& value, const char*) override {
    const YAML::Node n = take(key);
    if (!n) return;
    if (n.IsNull()) {
      value.clear();
      return;
    }
    if (!n.IsScalar()) fail(n, key, "expected a string, got " + show(n));
    value = n.Scalar();
  }

  void choice(const char* key, std::string& value, const std::vector<std::string>& choices,
              const char*) override {
    const YAML::Node n = take(key);
    if (!n) return;
    if (!n.IsScalar()) fail(n, key, "expected one of " + joinChoices(choices) + ", got " + show(n));
    const std::string v = n.Scalar();
    if (std::find(choices.begin(), choices.end(), v) == choices.end()) {
      std::string hint = closest(v, choices);
      fail(n, key,
           "value '" + v + "' is not one of " + joinChoices(choices) +
               (hint.empty() ? "" : " (did you mean '" + hint + "'?)"));
    }
    value = v;
  }

  void textList(const char* key, std::vector<std::string>& value, const char*) override {
    const YAML::Node n = take(key);
    if (!n) return;
    if (n.IsNull()) {
      value.clear();
      return;
    }
    if (!n.IsSequence()) fail(n, key, "expected a list of strings, got " + show(n));
    std::vector<std::string> out;
    for (const auto& item : n) {
      if (!item.IsScalar()) fail(item, key, "expected a list of strings, got " + show(item));
      out.push_back(item.Scalar());
    }
    value = out;
  }

  /// After bind(): every key present in the section must have been consumed.
  void checkUnknown() const {
    if (!section_ || section_.IsNull()) return;
    for (const auto& kv : section_) {
      const std::string k = kv.first.Scalar();
      if (!taken_.count(k)) {
        const std::string hint = closest(k, known_);
        throw ConfigError(where(origin_, kv.first) + ": unknown key '" + name_ + "." + k + "'" +
                          (hint.empty() ? "" : "; did you mean '" + name_ + "." + hint + "'?") +
                          " (`emf config --list` shows every key)");
      }
    }
  }

 private:
  YAML::Node take(const char* key) {
    known_.push_back(key);
    if (!section_ || section_.IsNull()) return YAML::Node(YAML::NodeType::Undefined);
    for (const auto& kv : section_) {
      if (kv.first.Scalar() == key) {
        taken_.insert(key);
        return kv.second;
      }
    }
    return YAML::Node(YAML::NodeType::Undefined);
  }

  static std::string show(const YAML::Node& n) {
    if (n.IsScalar()) return "'" + n.Scalar() + "'";
    if (n.IsSequence()) return "a list";
    if (n.IsMap()) return "a mapping";
    return "nothing";
  }

  [[noreturn]] void fail(const YAML::Node& n, const char* key, const std::string& what) const {
    throw ConfigError(where(origin_, n) + ": " + name_ + "." + key + ": " + what);
  }

  YAML::Node section_;
  std::string origin_;
  std::string name_;
  std::set<std::string> taken_;
  std::vector<std::string> known_;
};

/// Checks current values against their ranges.
class ValidateBinder : public OptionBinder {
 public:
  explicit ValidateBinder(std::string section) : name_(std::move(section)) {}
  void real(const char* key, double& v, double lo, double hi, const char* unit,
            const char*) override {
    if (!std::isfinite(v) || v < lo || v > hi) {
      throw ConfigError(name_ + "." + key + ": value " + formatNumber(v) + " is out of range " +
                        rangeText(lo, hi) + ((unit && *unit) ? std::string(" ") + unit : ""));
    }
  }
  void integer(const char* key, int& v, int lo, int hi, const char* unit, const char*) override {
    if (v < lo || v > hi) {
      throw ConfigError(name_ + "." + key + ": value " + std::to_string(v) + " is out of range " +
                        rangeText(lo, hi) + ((unit && *unit) ? std::string(" ") + unit : ""));
    }
  }
  void boolean(const char*, bool&, const char*) override {}
  void text(const char*, std::string&, const char*) override {}
  void choice(const char* key, std::string& v, const std::vector<std::string>& choices,
              const char*) override {
    if (std::find(choices.begin(), choices.end(), v) == choices.end()) {
      throw ConfigError(name_ + "." + key + ": value '" + v + "' is not one of " +
                        joinChoices(choices));
    }
  }
  void textList(const char*, std::vector<std::string>&, const char*) override {}

 private:
  std::string name_;
};

/// Lists keys with their documentation and current (default) values.
class ListBinder : public OptionBinder {
 public:
  ListBinder(std::string section, std::vector<OptionInfo>* out)
      : name_(std::move(section)), out_(out) {}
  void real(const char* key, double& v, double lo, double hi, const char* unit,
            const char* doc) override {
    add(key, "real", rangeText(lo, hi), unit, doc, formatNumber(v));
  }
  void integer(const char* key, int& v, int lo, int hi, const char* unit,
               const char* doc) override {
    add(key, "integer", rangeText(lo, hi), unit, doc, std::to_string(v));
  }
  void boolean(const char* key, bool& v, const char* doc) override {
    add(key, "boolean", "", "", doc, v ? "true" : "false");
  }
  void text(const char* key, std::string& v, const char* doc) override {
    add(key, "text", "", "", doc, "\"" + v + "\"");
  }
  void choice(const char* key, std::string& v, const std::vector<std::string>& choices,
              const char* doc) override {
    add(key, "choice", joinChoices(choices), "", doc, v);
  }
  void textList(const char* key, std::vector<std::string>& v, const char* doc) override {
    std::string s = "[";
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + ("\"" + v[i] + "\"");
    add(key, "list", "", "", doc, s + "]");
  }

 private:
  void add(const char* key, const char* type, std::string range, const char* unit, const char* doc,
           std::string def) {
    out_->push_back(
        {name_, key, type, std::move(range), unit ? unit : "", doc ? doc : "", std::move(def)});
  }
  std::string name_;
  std::vector<OptionInfo>* out_;
};

/// Emits the configuration as YAML.
class EmitBinder : public OptionBinder {
 public:
  explicit EmitBinder(YAML::Emitter& e) : e_(e) {}
  void real(const char* key, double& v, double, double, const char*, const char*) override {
    e_ << YAML::Key << key << YAML::Value << v;
  }
  void integer(const char* key, int& v, int, int, const char*, const char*) override {
    e_ << YAML::Key << key << YAML::Value << v;
  }
  void boolean(const char* key, bool& v, const char*) override {
    e_ << YAML::Key << key << YAML::Value << v;
  }
  void text(const char* key, std::string& v, const char*) override {
    e_ << YAML::Key << key << YAML::Value << YAML::DoubleQuoted << v;
  }
  void choice(const char* key, std::string& v, const std::vector<std::string>&,
              const char*) override {
    e_ << YAML::Key << key << YAML::Value << v;
  }
  void textList(const char* key, std::vector<std::string>& v, const char*) override {
    e_ << YAML::Key << key << YAML::Value << YAML::Flow << v;
  }

 private:
  YAML::Emitter& e_;
};

std::vector<std::string> sectionNames() {
  std::vector<std::string> names;
  Config c;
  c.forEachSection([&](const char* name, auto&) { names.push_back(name); });
  return names;
}

}  // namespace

int editDistance(const std::string& a, const std::string& b) {
  std::vector<int> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = static_cast<int>(j);
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = static_cast<int>(i);
    for (size_t j = 1; j <= b.size(); ++j) {
      const int sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

void Config::merge(const std::string& yaml, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + (hasLines(origin) ? ":" + std::to_string(e.mark.line + 1) : "") +
                      ": not valid YAML: " + e.msg);
  }
  if (!root || root.IsNull()) return;  // empty file: all defaults
  if (!root.IsMap()) {
    throw ConfigError(origin + ": expected a mapping of sections (cl:, map:, track:, ...)");
  }
  const std::vector<std::string> sections = sectionNames();
  rejectDuplicateKeys(root, origin, "");
  for (const auto& kv : root) {
    const std::string name = kv.first.Scalar();
    if (std::find(sections.begin(), sections.end(), name) == sections.end()) {
      const std::string hint = closest(name, sections);
      throw ConfigError(where(origin, kv.first) + ": unknown section '" + name + "'" +
                        (hint.empty() ? "" : "; did you mean '" + hint + "'?"));
    }
    if (!kv.second.IsMap() && !kv.second.IsNull()) {
      throw ConfigError(where(origin, kv.second) + ": section '" + name +
                        "' must be a mapping of keys");
    }
    rejectDuplicateKeys(kv.second, origin, name + ".");
  }
  forEachSection([&](const char* name, auto& options) {
    const YAML::Node section = root[name];
    YamlReadBinder reader(section, origin, name);
    options.bind(reader);
    reader.checkUnknown();
  });
}

Config Config::loadString(const std::string& yaml, const std::string& origin) {
  Config c;
  c.merge(yaml, origin);
  return c;
}

Config Config::loadFile(const std::string& path) {
  if (std::filesystem::is_directory(path)) {
    throw ConfigError(path +
                      ": is a folder, not a configuration file (give a .yaml file; presets "
                      "live in conf/)");
  }
  std::ifstream in(path);
  if (!in) {
    throw ConfigError(path +
                      ": cannot open the configuration file (check the path; presets "
                      "live in conf/)");
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return loadString(ss.str(), path);
}

void Config::set(const std::string& assignment) {
  const auto eq = assignment.find('=');
  const auto dot = assignment.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq) {
    throw ConfigError("--set '" + assignment + "': expected section.key=value");
  }
  const std::string section = assignment.substr(0, dot);
  const std::string key = assignment.substr(dot + 1, eq - dot - 1);
  const std::string value = assignment.substr(eq + 1);
  merge(section + ":\n  " + key + ": " + (value.empty() ? "\"\"" : value) + "\n",
        "--set " + assignment);
}

void Config::validate() const {
  Config copy = *this;
  copy.forEachSection([&](const char* name, auto& options) {
    ValidateBinder v(name);
    options.bind(v);
  });
}

std::string Config::toYaml() const {
  Config copy = *this;
  YAML::Emitter e;
  e << YAML::BeginMap;
  copy.forEachSection([&](const char* name, auto& options) {
    e << YAML::Key << name << YAML::Value << YAML::BeginMap;
    EmitBinder b(e);
    options.bind(b);
    e << YAML::EndMap;
  });
  e << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

std::vector<OptionInfo> listOptions() {
  std::vector<OptionInfo> out;
  Config c;
  c.forEachSection([&](const char* name, auto& options) {
    ListBinder b(name, &out);
    options.bind(b);
  });
  return out;
}

}  // namespace emf
