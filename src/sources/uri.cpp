#include "sources/uri.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>

#include "common/error.h"
#include "common/option_binder.h"

namespace emf::sources {
namespace {

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Decodes %XX escapes; a '%' not followed by two hex digits is kept literally.
std::string percentDecode(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && hexValue(s[i + 1]) >= 0 && hexValue(s[i + 2]) >= 0) {
      out.push_back(static_cast<char>(hexValue(s[i + 1]) * 16 + hexValue(s[i + 2])));
      i += 2;
    } else {
      out.push_back(s[i]);
    }
  }
  return out;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s.empty() ? "(none)" : s;
}

// Applies query values to an options struct through its bind() declaration, so the URI uses
// exactly the configuration's keys and ranges.
class QueryBinder : public OptionBinder {
 public:
  explicit QueryBinder(const UriQuery& q) : q_(q) {}
  void real(const char* key, double& value, double lo, double hi, const char*,
            const char*) override {
    if (auto v = q_.real(key, lo, hi)) value = *v;
  }
  void integer(const char* key, int& value, int lo, int hi, const char*, const char*) override {
    if (auto v = q_.integer(key, lo, hi)) value = *v;
  }
  void boolean(const char* key, bool& value, const char*) override {
    if (auto v = q_.text(key)) {
      if (*v == "1" || *v == "true") {
        value = true;
      } else if (*v == "0" || *v == "false") {
        value = false;
      } else {
        throw IoError("URI '" + q_.uri().text + "': query key '" + key +
                      "' must be true/false/1/0, got '" + *v + "'");
      }
    }
  }
  void text(const char* key, std::string& value, const char*) override {
    if (std::string(key) == "uri") return;
    if (auto v = q_.text(key)) value = *v;
  }
  void choice(const char* key, std::string& value, const std::vector<std::string>& choices,
              const char*) override {
    if (auto v = q_.text(key)) {
      if (std::find(choices.begin(), choices.end(), *v) == choices.end()) {
        throw IoError("URI '" + q_.uri().text + "': query key '" + key + "' must be one of " +
                      joined(choices) + ", got '" + *v + "'");
      }
      value = *v;
    }
  }
  void textList(const char*, std::vector<std::string>&, const char*) override {}

 private:
  const UriQuery& q_;
};

// Collects the key names of an options struct.
class KeyLister : public OptionBinder {
 public:
  std::vector<std::string> keys;
  void real(const char* k, double&, double, double, const char*, const char*) override {
    keys.push_back(k);
  }
  void integer(const char* k, int&, int, int, const char*, const char*) override {
    keys.push_back(k);
  }
  void boolean(const char* k, bool&, const char*) override { keys.push_back(k); }
  void text(const char* k, std::string&, const char*) override { keys.push_back(k); }
  void choice(const char* k, std::string&, const std::vector<std::string>&, const char*) override {
    keys.push_back(k);
  }
  void textList(const char* k, std::vector<std::string>&, const char*) override {
    keys.push_back(k);
  }
};

}  // namespace

Uri parseUri(const std::string& text) {
  Uri uri;
  uri.text = text;
  const size_t colon = text.find(':');
  const auto bad = [&](const std::string& why) {
    return IoError("source URI '" + text + "': " + why +
                   " (expected scheme:path[?key=value&...], e.g. tum:/data/fr3_walking?"
                   "depth_scale=5000; schemes: tum, cofusion, klg, synth, openni2, v4l2)");
  };
  if (colon == std::string::npos || colon == 0) throw bad("no scheme");
  for (size_t i = 0; i < colon; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (!std::isalnum(c) && c != '_' && c != '-') throw bad("malformed scheme");
    uri.scheme.push_back(static_cast<char>(std::tolower(c)));
  }
  const std::string rest = text.substr(colon + 1);
  const size_t qmark = rest.find('?');
  uri.path = percentDecode(rest.substr(0, qmark));
  if (qmark == std::string::npos) return uri;
  const std::string query = rest.substr(qmark + 1);
  size_t start = 0;
  while (start <= query.size()) {
    size_t amp = query.find('&', start);
    if (amp == std::string::npos) amp = query.size();
    const std::string item = query.substr(start, amp - start);
    start = amp + 1;
    if (item.empty()) continue;  // tolerate "?a=1&&b=2" and a trailing '&'
    const size_t eq = item.find('=');
    if (eq == std::string::npos) throw bad("query item '" + item + "' has no '=value'");
    const std::string key = percentDecode(item.substr(0, eq));
    if (key.empty()) throw bad("query item '" + item + "' has an empty key");
    if (uri.query.count(key)) throw bad("query key '" + key + "' given twice");
    uri.query[key] = percentDecode(item.substr(eq + 1));
  }
  return uri;
}

UriQuery::UriQuery(const Uri& uri, std::vector<std::string> valid_keys)
    : uri_(uri), valid_keys_(std::move(valid_keys)) {
  std::sort(valid_keys_.begin(), valid_keys_.end());
  for (const auto& kv : uri_.query) {
    if (!std::binary_search(valid_keys_.begin(), valid_keys_.end(), kv.first)) {
      throw IoError("source URI '" + uri_.text + "': unknown query key '" + kv.first +
                    "' for scheme '" + uri_.scheme + ":'; valid keys: " + joined(valid_keys_));
    }
  }
}

std::optional<std::string> UriQuery::text(const std::string& key) const {
  auto it = uri_.query.find(key);
  if (it == uri_.query.end()) return std::nullopt;
  return it->second;
}

std::optional<double> UriQuery::real(const std::string& key, double lo, double hi) const {
  auto s = text(key);
  if (!s) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(s->c_str(), &end);
  if (s->empty() || *end != '\0' || !std::isfinite(v)) {
    throw IoError("source URI '" + uri_.text + "': query key '" + key +
                  "' must be a number, got '" + *s + "'");
  }
  if (v < lo || v > hi) {
    throw IoError("source URI '" + uri_.text + "': query key '" + key + "' = " + *s +
                  " is outside its range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return v;
}

std::optional<int> UriQuery::integer(const std::string& key, int lo, int hi) const {
  auto s = text(key);
  if (!s) return std::nullopt;
  char* end = nullptr;
  const long v = std::strtol(s->c_str(), &end, 10);
  if (s->empty() || *end != '\0') {
    throw IoError("source URI '" + uri_.text + "': query key '" + key +
                  "' must be an integer, got '" + *s + "'");
  }
  if (v < lo || v > hi) {
    throw IoError("source URI '" + uri_.text + "': query key '" + key + "' = " + *s +
                  " is outside its range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return static_cast<int>(v);
}

std::vector<std::string> sourceQueryKeys() {
  KeyLister lister;
  core::SourceOptions o;
  o.bind(lister);
  std::vector<std::string> keys;
  for (const auto& k : lister.keys) {
    if (k != "uri") keys.push_back(k);
  }
  return keys;
}

core::SourceOptions applySourceQuery(const UriQuery& query, core::SourceOptions options) {
  QueryBinder binder(query);
  options.bind(binder);
  return options;
}

}  // namespace emf::sources
