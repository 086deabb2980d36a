#include "firmware_host/sensor_uri.h"

#include <cmath>
#include <cstdlib>

#include "common/error.h"

namespace emf::fw {

SensorUri::SensorUri(const std::string& uri) : uri_(uri) {
  const size_t colon = uri.find(':');
  if (colon == std::string::npos || colon == 0) {
    throw IoError("source URI '" + uri +
                  "' has no scheme: use openni2:[device] or "
                  "v4l2:/dev/videoN[,/dev/videoM]");
  }
  scheme_ = uri.substr(0, colon);
  std::string rest = uri.substr(colon + 1);
  const size_t q = rest.rfind('?');
  if (q != std::string::npos) {
    const std::string query = rest.substr(q + 1);
    rest = rest.substr(0, q);
    size_t pos = 0;
    while (pos <= query.size()) {
      size_t amp = query.find('&', pos);
      if (amp == std::string::npos) amp = query.size();
      const std::string kv = query.substr(pos, amp - pos);
      pos = amp + 1;
      if (kv.empty()) continue;
      const size_t eq = kv.find('=');
      if (eq == std::string::npos || eq == 0) {
        throw IoError("source URI '" + uri + "': parameter '" + kv + "' is not key=value");
      }
      params_[kv.substr(0, eq)] = kv.substr(eq + 1);
    }
  }
  target_ = rest;
}

std::string SensorUri::text(const std::string& key, const std::string& fallback) {
  known_.insert(key);
  auto it = params_.find(key);
  return it == params_.end() ? fallback : it->second;
}

double SensorUri::real(const std::string& key, double fallback, double lo, double hi) {
  known_.insert(key);
  auto it = params_.find(key);
  if (it == params_.end()) return fallback;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str() || *end != '\0' || !std::isfinite(v) || v < lo || v > hi) {
    throw IoError("source URI '" + uri_ + "': " + key + "=" + it->second +
                  " must be a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return v;
}

int SensorUri::integer(const std::string& key, int fallback, int lo, int hi) {
  known_.insert(key);
  auto it = params_.find(key);
  if (it == params_.end()) return fallback;
  char* end = nullptr;
  const long v = std::strtol(it->second.c_str(), &end, 10);
  if (end == it->second.c_str() || *end != '\0' || v < lo || v > hi) {
    throw IoError("source URI '" + uri_ + "': " + key + "=" + it->second +
                  " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                  "]");
  }
  return static_cast<int>(v);
}

bool SensorUri::flag(const std::string& key, bool fallback) {
  known_.insert(key);
  auto it = params_.find(key);
  if (it == params_.end()) return fallback;
  if (it->second == "1" || it->second == "true") return true;
  if (it->second == "0" || it->second == "false") return false;
  throw IoError("source URI '" + uri_ + "': " + key + "=" + it->second + " must be 0 or 1");
}

void SensorUri::checkAllUsed() const {
  for (const auto& kv : params_) {
    if (known_.count(kv.first)) continue;
    std::string keys;
    for (const auto& k : known_) keys += (keys.empty() ? "" : ", ") + k;
    throw IoError("source URI '" + uri_ + "': unknown parameter '" + kv.first + "' for " + scheme_ +
                  ": (known: " + keys + ")");
  }
}

}  // namespace emf::fw
