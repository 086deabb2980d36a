#include <chrono>
#include <cstdio>

#include "cl/context.h"
#include "cl/embedded_kernels.h"
#include "cli/arg_parser.h"
#include "cli/commands.h"
#include "cli/load_config.h"
#include "emf/emf.h"
#include "pipeline/plugin_search_path.h"

namespace emf::cli {
namespace {

std::vector<std::string> sensorBackends() {
  std::vector<std::string> b;
#ifdef EMF_HAVE_OPENNI2
  b.push_back("openni2");
#endif
#ifdef EMF_HAVE_V4L2
  b.push_back("v4l2");
#endif
#ifdef EMF_HAVE_LIBUSB
  b.push_back("libusb (device discovery)");
#endif
  return b;
}

}  // namespace

int cmdInfo(const std::vector<std::string>& args) {
  std::string config_file;
  std::vector<std::string> sets;
  bool no_kernels = false;
  ArgParser p("info",
              "Prints the version, every OpenCL platform/device (marking the one the "
              "configuration selects), the compiled-in sensor backends and the plugin search "
              "path, then builds every embedded kernel on the selected device, reporting how "
              "many came from the on-disk cache.");
  p.option("config", &config_file, "FILE", "YAML configuration (cl.* selects the device)");
  p.repeated("set", &sets, "SECTION.KEY=VALUE", "override one key, e.g. cl.device_type=cpu");
  p.flag("no-kernels", &no_kernels, "do not build the kernels");
  if (auto code = p.parse(args)) return *code;
  const Config config = loadConfig(config_file, sets);

  std::printf("emf %d.%d.%d (API %d)\n\n", EMF_VERSION_MAJOR, EMF_VERSION_MINOR, EMF_VERSION_PATCH,
              EMF_API_VERSION);
  const auto devices = cl::listDevices();
  std::printf("OpenCL devices:\n");
  if (devices.empty()) std::printf("  (none: %s)\n", cl::noDeviceAdvice().c_str());
  cl::Context ctx(config.cl);
  for (const auto& d : devices) {
    const bool selected = d.device == ctx.deviceId();
    std::printf("  %s %s\n", selected ? "*" : " ", d.describe().c_str());
  }
  std::printf("selected: %s\n  reason: %s\n\n", ctx.device().device_name.c_str(),
              ctx.selection().reason.c_str());

  const auto backends = sensorBackends();
  std::printf("sensor backends:");
  if (backends.empty()) std::printf(" none compiled in");
  for (const auto& b : backends) std::printf(" %s", b.c_str());
  std::printf("\nplugin search path:\n");
  for (const auto& dir : pipeline::pluginSearchPath(config.detector)) {
    std::printf("  %s\n", dir.c_str());
  }
  std::printf("kernel cache: %s%s\n", ctx.cache().dir().c_str(),
              ctx.cache().enabled() ? "" : " (disabled)");

  if (!no_kernels) {
    const auto t0 = std::chrono::steady_clock::now();
    for (const cl::KernelSource* k : cl::embeddedKernels()) ctx.program(k->name);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const auto s = ctx.cacheStats();
    std::printf(
        "kernels: %zu files built in %.0f ms: %d loaded from cache, %d compiled from "
        "source (%d stored)\n",
        cl::embeddedKernels().size(), ms, s.disk_hits, s.compiled, s.stored);
  }
  return kExitOk;
}

}  // namespace emf::cli
