#include <cstring>
#include <memory>

#include "capi/firewall.h"
#include "capi/system_impl.h"
#include "emf/emf.h"

namespace {

bool apiVersionSupported(uint32_t caller) {
  const uint32_t major = caller / 10000, minor = (caller / 100) % 100;
  return major == EMF_VERSION_MAJOR && minor <= EMF_VERSION_MINOR;
}

void copyString(char* dst, size_t size, const std::string& src) {
  std::strncpy(dst, src.c_str(), size - 1);
  dst[size - 1] = '\0';
}

}  // namespace

extern "C" {

EMF_API void emf_system_options_init(emf_system_options* options) {
  if (!options) return;
  std::memset(options, 0, sizeof(*options));
  options->struct_size = sizeof(*options);
  options->api_version = EMF_API_VERSION;
}

EMF_API emf_status emf_system_create(const emf_system_options* options, emf_system** out) {
  return emf::capi::guard("emf_system_create", [&]() -> emf_status {
    if (!out) return emf::capi::fail(EMF_ERROR_INVALID_ARGUMENT, "emf_system_create: out is NULL");
    *out = nullptr;
    const emf_status s = emf::capi::checkStruct(
        options, options ? options->struct_size : 0,
        offsetof(emf_system_options, config_yaml) + sizeof(options->config_yaml),
        "emf_system_options", "emf_system_create");
    if (s != EMF_OK) return s;
    if (!apiVersionSupported(options->api_version)) {
      return emf::capi::fail(EMF_ERROR_VERSION_MISMATCH,
                             "emf_system_create: caller compiled against API " +
                                 std::to_string(options->api_version) + ", library is " +
                                 std::to_string(EMF_VERSION) +
                                 " (same major, minor <= library's required)");
    }
    auto sys = std::make_unique<emf_system>();
    if (options->config_file) sys->config = emf::Config::loadFile(options->config_file);
    if (options->config_yaml) sys->config.merge(options->config_yaml, "<config_yaml>");
    sys->config.validate();
    sys->cl = std::make_unique<emf::cl::Context>(sys->config.cl);
    *out = sys.release();
    return EMF_OK;
  });
}

EMF_API void emf_system_destroy(emf_system* system) {
  if (!system) return;
  try {
    delete system;
  } catch (...) {
    // Destructors do not throw; nothing may cross the boundary regardless.
  }
}

EMF_API emf_status emf_system_get_info(const emf_system* system, emf_system_info* info) {
  return emf::capi::guard("emf_system_get_info", [&]() -> emf_status {
    if (!system) {
      return emf::capi::fail(EMF_ERROR_INVALID_ARGUMENT, "emf_system_get_info: system is NULL");
    }
    const emf_status s =
        emf::capi::checkStruct(info, info ? info->struct_size : 0, sizeof(emf_system_info),
                               "emf_system_info", "emf_system_get_info");
    if (s != EMF_OK) return s;
    const auto& d = system->cl->device();
    copyString(info->device_name, sizeof(info->device_name), d.device_name);
    copyString(info->platform_name, sizeof(info->platform_name), d.platform_name);
    info->device_is_fallback = system->cl->selection().fallback ? 1 : 0;
    return EMF_OK;
  });
}

}  // extern "C"
