// openSource(): the URI dispatcher (sources/open_source.h).
#include "sources/open_source.h"

#include <algorithm>

#include "common/error.h"
#include "firmware_host/sensor_sources.h"
#include "io/cofusion_source.h"
#include "io/klg.h"
#include "io/tum_source.h"
#include "sources/uri.h"
#include "synth/synth_source.h"

namespace emf::sources {
namespace {

std::vector<std::string> withKeys(std::vector<std::string> keys,
                                  std::initializer_list<const char*> extra) {
  for (const char* k : extra) keys.push_back(k);
  return keys;
}

std::vector<std::string> without(std::vector<std::string> keys,
                                 std::initializer_list<const char*> drop) {
  for (const char* k : drop) keys.erase(std::remove(keys.begin(), keys.end(), k), keys.end());
  return keys;
}

void requirePath(const Uri& uri, const char* what) {
  if (uri.path.empty()) {
    throw IoError("source URI '" + uri.text + "': missing " + what + " after '" + uri.scheme +
                  ":'");
  }
}

std::unique_ptr<core::FrameSource> openAnySource(const std::string& uri_text,
                                                 const core::SourceOptions& options);

}  // namespace

std::unique_ptr<core::FrameSource> openSource(const std::string& uri_text,
                                              const core::SourceOptions& options) {
  std::unique_ptr<core::FrameSource> source = openAnySource(uri_text, options);
  // Before the first frame is processed: a huge image would take seconds and gigabytes to fail.
  const core::Intrinsics k = source->intrinsics();
  const int64_t pixels = static_cast<int64_t>(k.width) * k.height;
  if (pixels > options.max_pixels) {
    throw IoError("source '" + uri_text + "': depth images of " + std::to_string(k.width) + "x" +
                  std::to_string(k.height) + " = " + std::to_string(pixels) +
                  " pixels are more than source.max_pixels (" + std::to_string(options.max_pixels) +
                  "); downscale the images, or raise source.max_pixels (memory and time per "
                  "frame grow with it)");
  }
  return source;
}

namespace {

std::unique_ptr<core::FrameSource> openAnySource(const std::string& uri_text,
                                                 const core::SourceOptions& options) {
  const Uri uri = parseUri(uri_text);
  const std::vector<std::string> base = sourceQueryKeys();

  if (uri.scheme == "tum") {
    requirePath(uri, "dataset folder");
    const UriQuery q(uri, base);
    return std::make_unique<io::TumSource>(uri.path, applySourceQuery(q, options));
  }
  if (uri.scheme == "cofusion") {
    requirePath(uri, "dataset folder");
    const UriQuery q(uri, withKeys(without(base, {"depth_scale", "max_time_diff_s"}), {"fps"}));
    const double fps = q.real("fps", 0.001, 1000.0).value_or(30.0);
    return std::make_unique<io::CoFusionSource>(uri.path, applySourceQuery(q, options), fps);
  }
  if (uri.scheme == "klg") {
    requirePath(uri, "log file");
    const UriQuery q(uri, withKeys(without(base, {"max_time_diff_s"}), {"width", "height"}));
    // KLG depth is millimetres by definition: the config's depth_scale (a TUM default) does
    // not apply; only an explicit ?depth_scale= changes it.
    const double depth_scale = q.real("depth_scale", 1.0, 1e6).value_or(io::kKlgDepthScale);
    const cv::Size size(q.integer("width", 1, 100000).value_or(640),
                        q.integer("height", 1, 100000).value_or(480));
    return std::make_unique<io::KlgSource>(uri.path, applySourceQuery(q, options), size,
                                           depth_scale);
  }
  if (uri.scheme == "synth") {
    requirePath(uri, "preset name");
    return synth::openSynthSource(uri.path, uri.query, options);
  }
  if (uri.scheme == "openni2" || uri.scheme == "v4l2") {
    return fw::openSensorSource(uri_text, options);
  }
  throw IoError("source URI '" + uri.text + "': unknown scheme '" + uri.scheme +
                ":'; use tum:<dir>, cofusion:<dir>, klg:<file>, synth:<preset>, openni2:[uri] "
                "or v4l2:/dev/videoN");
}

}  // namespace

}  // namespace emf::sources
