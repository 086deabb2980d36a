// Parsing of live-sensor URIs: `<scheme>:<target>[?key=value&key=value]`. Every parameter must be
// consumed by the source that opens the URI; unknown ones are errors naming the URI and the known
// keys, so a typo never silently falls back to a default.
#pragma once

#include <map>
#include <set>
#include <string>

namespace emf::fw {

class SensorUri {
 public:
  /// Splits `uri` at the first ':' (scheme) and the last '?' (query). Throws IoError for a URI
  /// without scheme or a malformed query.
  explicit SensorUri(const std::string& uri);

  const std::string& uri() const { return uri_; }
  const std::string& scheme() const { return scheme_; }
  /// What follows "scheme:" without the query ("" when absent).
  const std::string& target() const { return target_; }

  bool has(const std::string& key) const { return params_.count(key) != 0; }
  /// Value of `key` as text / number / integer / 0|1 flag, or `fallback` when absent. Throws
  /// IoError naming the URI, key and accepted range for a malformed value.
  std::string text(const std::string& key, const std::string& fallback);
  double real(const std::string& key, double fallback, double lo, double hi);
  int integer(const std::string& key, int fallback, int lo, int hi);
  bool flag(const std::string& key, bool fallback);
  /// Throws IoError if a parameter was never asked for (listing the keys that were).
  void checkAllUsed() const;

 private:
  std::string uri_, scheme_, target_;
  std::map<std::string, std::string> params_;
  std::set<std::string> known_;
};

}  // namespace emf::fw
