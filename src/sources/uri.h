// Source URIs: `scheme:path?key=value&key=value` (e.g. `tum:/data/fr3?depth_scale=1000&fx=585`).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/source_options.h"

namespace emf::sources {

/// A parsed source URI. `path` and query values are percent-decoded (%3F = '?', %26 = '&').
struct Uri {
  std::string text;    // the URI as given (for messages)
  std::string scheme;  // lower-case, without ':'
  std::string path;    // may be empty (e.g. `openni2:`)
  std::map<std::string, std::string> query;
};

/// Parses `scheme:path[?key=value[&key=value...]]`. Throws IoError naming the URI for a missing
/// or malformed scheme, an empty or duplicated query key, or a key without '='.
Uri parseUri(const std::string& text);

/// Typed, validated access to a URI's query parameters.
class UriQuery {
 public:
  /// Throws IoError naming the first key of `uri` not in `valid_keys`, listing the valid ones.
  UriQuery(const Uri& uri, std::vector<std::string> valid_keys);

  bool has(const std::string& key) const { return uri_.query.count(key) > 0; }
  /// The value as a number in [lo, hi]; nullopt if absent. Throws IoError naming key and URI.
  std::optional<double> real(const std::string& key, double lo, double hi) const;
  /// The value as an integer in [lo, hi]; nullopt if absent. Throws IoError naming key and URI.
  std::optional<int> integer(const std::string& key, int lo, int hi) const;
  /// The raw value; nullopt if absent.
  std::optional<std::string> text(const std::string& key) const;

  const Uri& uri() const { return uri_; }

 private:
  Uri uri_;
  std::vector<std::string> valid_keys_;
};

/// The SourceOptions keys a URI query may override (every key of section `source` but `uri`).
std::vector<std::string> sourceQueryKeys();

/// `options` with every SourceOptions key present in `query` replaced by its value (same
/// ranges as the configuration). Throws IoError for bad values.
core::SourceOptions applySourceQuery(const UriQuery& query, core::SourceOptions options);

}  // namespace emf::sources
