// Errors of live sensors, on top of emf's error types (src/common/error.h).
#pragma once

#include "common/error.h"

namespace emf::fw {

/// A live sensor stopped delivering frames: unplugged, powered off, or its stream stalled for
/// longer than the source's frame timeout. The message names the device and what to do. A
/// ReconnectingSource turns this into an error state and resumes when the sensor is back.
class SensorDisconnected : public IoError {
 public:
  using IoError::IoError;
};

}  // namespace emf::fw
