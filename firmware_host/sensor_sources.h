// Entry point of the live-sensor backends for sources::openSource(): `openni2:` and `v4l2:` URIs.
#pragma once

#include <memory>
#include <string>

#include "core/frame_source.h"

namespace emf::fw {

/// True for URIs this module opens (schemes openni2 and v4l2).
bool isSensorUri(const std::string& uri);

/// Opens a live sensor or recording: `openni2:[device|file.oni][?...]` (firmware_host/openni2/
/// openni2_source.h) or `v4l2:/dev/videoN[,/dev/videoM][?...]` (firmware_host/v4l2/
/// v4l2_source.h). Live devices are wrapped in a ReconnectingSource when `reconnect` is true
/// (URI parameter `reconnect=0` disables it). Throws IoError for unknown schemes, backends not
/// compiled in (naming the CMake option), and everything the backends report.
std::unique_ptr<core::FrameSource> openSensorSource(const std::string& uri,
                                                    const core::SourceOptions& options);

}  // namespace emf::fw
