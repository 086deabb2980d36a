// The object behind the opaque emf_system handle.
#pragma once

#include <memory>

#include "cl/context.h"
#include "common/config.h"

struct emf_system {
  emf::Config config;
  std::unique_ptr<emf::cl::Context> cl;
};
