#include "firmware_host/sensor_sources.h"

#include "common/error.h"
#include "firmware_host/reconnecting_source.h"
#include "firmware_host/sensor_uri.h"
#ifdef EMF_HAVE_OPENNI2
#include "firmware_host/openni2/openni2_source.h"
#endif
#ifdef EMF_HAVE_V4L2
#include "firmware_host/v4l2/v4l2_source.h"
#endif

namespace emf::fw {
namespace {

/// Removes `reconnect=...` from the query (it belongs to this layer, not to the backend).
std::string stripReconnect(const std::string& uri, bool* reconnect) {
  *reconnect = true;
  const size_t q = uri.rfind('?');
  if (q == std::string::npos) return uri;
  std::string out = uri.substr(0, q);
  std::string query;
  size_t pos = q + 1;
  while (pos <= uri.size()) {
    size_t amp = uri.find('&', pos);
    if (amp == std::string::npos) amp = uri.size();
    const std::string kv = uri.substr(pos, amp - pos);
    pos = amp + 1;
    if (kv.rfind("reconnect=", 0) == 0) {
      const std::string v = kv.substr(10);
      if (v != "0" && v != "1") {
        throw IoError("source URI '" + uri + "': reconnect=" + v + " must be 0 or 1");
      }
      *reconnect = v == "1";
    } else if (!kv.empty()) {
      query += (query.empty() ? "" : "&") + kv;
    }
  }
  return query.empty() ? out : out + "?" + query;
}

}  // namespace

bool isSensorUri(const std::string& uri) {
  return uri.rfind("openni2:", 0) == 0 || uri.rfind("v4l2:", 0) == 0;
}

std::unique_ptr<core::FrameSource> openSensorSource(const std::string& uri,
                                                    const core::SourceOptions& options) {
  bool reconnect = true;
  const std::string inner_uri = stripReconnect(uri, &reconnect);
  (void)options;  // unused when no backend is compiled in
  ReconnectingSource::Factory factory;
  if (uri.rfind("openni2:", 0) == 0) {
#ifdef EMF_HAVE_OPENNI2
    factory = [inner_uri, options] { return std::make_unique<Openni2Source>(inner_uri, options); };
#else
    throw IoError("'" + uri + "': emf was built without OpenNI2 (CMake option EMF_WITH_OPENNI2)");
#endif
  } else if (uri.rfind("v4l2:", 0) == 0) {
#ifdef EMF_HAVE_V4L2
    factory = [inner_uri, options] { return std::make_unique<V4l2Source>(inner_uri, options); };
#else
    throw IoError("'" + uri + "': emf was built without V4L2 (CMake option EMF_WITH_V4L2)");
#endif
  } else {
    throw IoError("'" + uri + "' is not a sensor URI (openni2:..., v4l2:...)");
  }
  std::unique_ptr<core::FrameSource> source = factory();
  if (!reconnect || !source->isLive()) return source;
  // The first open above proves the URI works; the wrapper re-opens it after an unplug.
  auto first = std::make_shared<std::unique_ptr<core::FrameSource>>(std::move(source));
  return std::make_unique<ReconnectingSource>(
      [first, factory]() -> std::unique_ptr<core::FrameSource> {
        if (*first) return std::move(*first);
        return factory();
      },
      uri);
}

}  // namespace emf::fw
