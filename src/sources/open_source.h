// Opens any source from its URI: the datasets (io), the synthetic world (synth) and the
// sensors (firmware_host) behind the one FrameSource interface of core.
#pragma once

#include <memory>
#include <string>

#include "core/frame_source.h"
#include "core/source_options.h"

namespace emf::sources {

/// Opens a source from a URI: `tum:<dir>`, `cofusion:<dir>`, `klg:<file>`,
/// `synth:<preset>[?frames=N&seed=S]`, `openni2:[<uri>]`, `v4l2:/dev/videoN[,/dev/videoM]`.
/// Query parameters (`?depth_scale=1000&fx=585`) override `options`. Throws IoError for an
/// unknown scheme or unreadable input, naming what to fix.
std::unique_ptr<core::FrameSource> openSource(const std::string& uri,
                                              const core::SourceOptions& options);

}  // namespace emf::sources
