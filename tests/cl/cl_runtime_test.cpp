// The OpenCL runtime on the CI device (PoCL CPU): selection, kernel path vs CPU reference,
// the on-disk program cache, build errors with logs.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <utility>

#include "cl/device.h"
#include "cl/embedded_kernels.h"
#include "cl/image_scale.h"
#include "cl/kernel_profile.h"
#include "common/error.h"
#include "test_support.h"

namespace emf::cl {
namespace {

// Float affine maps are exact up to one rounding per operation (a*v+b may be fused).
constexpr float kScaleRelTolerance = 2e-7f;

class ClRuntime : public test::WithClQueue {};

TEST_F(ClRuntime, DefaultSelectionIsPoclCpuInCi) {
  // CI has only PoCL; a developer machine with a GPU selects its first device instead.
  if (listDevices().size() == 1) {
    EXPECT_TRUE(ctx().device().is_pocl) << ctx().device().describe();
    EXPECT_EQ(ctx().device().type, "cpu");
  }
  EXPECT_FALSE(ctx().device().device_name.empty());
}

TEST(ClDeviceInfo, PoclTargetComesFromTheVersionOrTheDeviceName) {
  DeviceInfo d;
  d.is_pocl = true;
  d.type = "cpu";
  const std::pair<const char*, const char*> cases[] = {
      {"pthread-skylake-avx512-Intel(R) Xeon(R) Processor", "skylake-avx512"},
      {"cpu-haswell-AMD EPYC 7B13 64-Core Processor", "haswell"},
      {"cpu-cortex-a76-ARM Cortex-A76", "cortex-a76"},
      {"cpu-generic-0x41", "generic"},
  };
  for (const auto& [name, target] : cases) {
    d.device_name = name;
    EXPECT_EQ(d.poclTarget(), target) << name;
  }
  // PoCL's version string names it when it has a host string (HSTR), also where PoCL did not
  // recognise the CPU (aarch64 under qemu: device name "pthread").
  d.device_name = "pthread";
  d.device_version = "OpenCL 3.0 PoCL HSTR: pthread-aarch64-unknown-linux-gnu-(null)";
  EXPECT_EQ(d.poclTarget(), "aarch64-unknown-linux-gnu-(null)");
  d.device_version = "OpenCL 3.0 PoCL HSTR: pthread-x86_64-pc-linux-gnu-skylake-avx512 extra";
  EXPECT_EQ(d.poclTarget(), "x86_64-pc-linux-gnu-skylake-avx512");
  d.device_name = "NVIDIA GeForce RTX 3060";
  d.type = "gpu";
  d.is_pocl = false;
  EXPECT_EQ(d.poclTarget(), "");
}

TEST_F(ClRuntime, DescriptionNamesTheTargetAndTheVectorWidths) {
  const DeviceInfo& d = ctx().device();
  EXPECT_GT(d.native_vector_width_float, 0u);
  EXPECT_GT(d.native_vector_width_int, 0u);
  EXPECT_NE(
      d.describe().find("native vector width float " + std::to_string(d.native_vector_width_float)),
      std::string::npos)
      << d.describe();
  EXPECT_NE(ctx().describe().find(", kernel lanes " + std::to_string(ctx().lanes())),
            std::string::npos)
      << ctx().describe();
  if (d.is_pocl && d.type == "cpu") {
    EXPECT_FALSE(d.poclTarget().empty()) << d.device_name;
    EXPECT_NE(d.describe().find("target " + d.poclTarget()), std::string::npos) << d.describe();
  }
}

TEST(ClLanes, TheKeyChoosesTheWidthAndTheProgramsAreBuiltWithIt) {
  EXPECT_EQ(ClOptions{}.lanes, "16");
  ClOptions o;
  o.lanes = "8";
  Context eight(o);
  EXPECT_EQ(eight.lanes(), 8);
  EXPECT_NE(eight.programOptions().find("-DEMF_W=8"), std::string::npos) << eight.programOptions();
  EXPECT_NO_THROW(eight.program("track_reduce", "-Werror"));
  o.lanes = "12";
  try {
    Context twelve(o);
    FAIL() << "12 lanes accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cl.lanes"), std::string::npos) << e.what();
  }
}

TEST(ClSelection, UnmatchedPreferenceFallsBackToPoclCpu) {
  ClOptions o;
  o.device = "no-such-device-xyz";
  const DeviceSelection s = selectDevice(o);
  EXPECT_TRUE(s.fallback);
  EXPECT_NE(s.reason.find("no-such-device-xyz"), std::string::npos) << s.reason;
  bool have_pocl_cpu = false;
  for (const auto& d : listDevices()) have_pocl_cpu |= d.is_pocl && d.type == "cpu";
  if (have_pocl_cpu) {
    EXPECT_TRUE(s.device.is_pocl);
    EXPECT_NE(s.reason.find("PoCL CPU"), std::string::npos) << s.reason;
  }
}

TEST(ClSelection, SubstringAndTypeMatch) {
  const auto devices = listDevices();
  ASSERT_FALSE(devices.empty());
  ClOptions o;
  o.device = devices.back().device_name.substr(0, 4);
  o.device_type = DeviceType::kAny;
  for (const auto& [type, name] : deviceTypeNames()) {
    if (devices.back().type == name) o.device_type = type;
  }
  const DeviceSelection s = selectDevice(o);
  EXPECT_FALSE(s.fallback) << s.reason;
  EXPECT_NE(s.device.device_name.find(o.device), std::string::npos);
}

TEST(ClErrors, NoDeviceAdviceNamesAnUncreatablePoclCache) {
  // PoCL (installed here: CI runs on it) reports no platform when it cannot create its kernel
  // cache folder; the advice must say so instead of "install an ICD". A folder below a file can
  // never be created, whoever runs the test.
  ASSERT_TRUE(std::filesystem::exists("/etc/OpenCL/vendors/pocl.icd"));
  const std::string dir = test::tempDir("pocl-advice");
  std::ofstream(dir + "/a_file") << "x";
  const char* old = std::getenv("POCL_CACHE_DIR");
  const std::string saved = old ? old : "";
  ::setenv("POCL_CACHE_DIR", (dir + "/a_file/pocl").c_str(), 1);
  const std::string blocked = noDeviceAdvice();
  ::setenv("POCL_CACHE_DIR", (dir + "/cache/pocl").c_str(), 1);
  const std::string writable = noDeviceAdvice();
  if (old) {
    ::setenv("POCL_CACHE_DIR", saved.c_str(), 1);
  } else {
    ::unsetenv("POCL_CACHE_DIR");
  }
  EXPECT_NE(blocked.find("cannot create its kernel cache folder '" + dir + "/a_file/pocl'"),
            std::string::npos)
      << blocked;
  EXPECT_NE(blocked.find("set POCL_CACHE_DIR"), std::string::npos) << blocked;
  EXPECT_NE(writable.find("install pocl-opencl-icd"), std::string::npos) << writable;
}

TEST(ClErrors, NamesAndMessages) {
  EXPECT_STREQ(errorName(CL_INVALID_VALUE), "CL_INVALID_VALUE");
  EXPECT_STREQ(errorName(CL_BUILD_PROGRAM_FAILURE), "CL_BUILD_PROGRAM_FAILURE");
  EXPECT_STREQ(errorName(-12345), "CL_UNKNOWN_ERROR");
  try {
    EMF_CL_CHECK(CL_OUT_OF_RESOURCES);
    FAIL();
  } catch (const ClError& e) {
    EXPECT_EQ(e.code(), CL_OUT_OF_RESOURCES);
    EXPECT_NE(std::string(e.what()).find("CL_OUT_OF_RESOURCES (-5)"), std::string::npos);
  }
}

TEST_F(ClRuntime, ScaleImageMatchesCpuReference) {
  const int n = 640 * 480 + 13;  // not a multiple of the work-group size
  std::vector<float> in(n);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.f, 65535.f);
  for (int i = 0; i < n; ++i)
    in[i] = (i % 97 == 0) ? std::numeric_limits<float>::quiet_NaN() : u(rng);
  const float a = 1.0f / 5000.0f, b = 0.25f;
  MemHandle din = ctx().buffer(CL_MEM_READ_ONLY, n * sizeof(float), in.data());
  MemHandle dout = ctx().buffer(CL_MEM_WRITE_ONLY, n * sizeof(float));
  scaleImage(ctx(), din, dout, n, a, b);
  std::vector<float> out(n);
  ctx().read(dout, out.data(), n * sizeof(float));
  const std::vector<float> ref = scaleImageReference(in, a, b);
  int nan_count = 0;
  for (int i = 0; i < n; ++i) {
    if (std::isnan(ref[i])) {
      ASSERT_TRUE(std::isnan(out[i])) << "pixel " << i << " must stay invalid";
      ++nan_count;
      continue;
    }
    ASSERT_NEAR(out[i], ref[i], kScaleRelTolerance * std::abs(ref[i]) + 1e-7f) << "pixel " << i;
  }
  EXPECT_EQ(nan_count, (n + 96) / 97);
}

TEST(ClKernelProfile, CountsEachKernelsLaunchesAndTheirDeviceTime) {
  ClOptions options;
  setKernelProfiling(true);
  Context ctx(options);  // created while the profile is on: a profiling queue
  const int n = 640 * 480;
  std::vector<float> in(n, 2.0f);
  MemHandle din = ctx.buffer(CL_MEM_READ_ONLY, n * sizeof(float), in.data());
  MemHandle dout = ctx.buffer(CL_MEM_WRITE_ONLY, n * sizeof(float));
  takeKernelProfile();  // whatever earlier tests launched
  constexpr int kLaunches = 3;
  for (int i = 0; i < kLaunches; ++i) scaleImage(ctx, din, dout, n, 0.5f, 1.0f);
  const std::map<std::string, KernelTime> profile = takeKernelProfile();
  ASSERT_EQ(profile.size(), 1u);
  ASSERT_EQ(profile.count("scale_image"), 1u);
  EXPECT_EQ(profile.at("scale_image").launches, kLaunches);
  // Three passes over 1.2 MB: more than nothing, less than a second on any device.
  EXPECT_GT(profile.at("scale_image").device_ms, 0.0);
  EXPECT_LT(profile.at("scale_image").device_ms, 1000.0);
  // The profile starts again from zero, and launches made with it off are not counted.
  EXPECT_TRUE(takeKernelProfile().empty());
  setKernelProfiling(false);
  scaleImage(ctx, din, dout, n, 0.5f, 1.0f);
  ctx.finish();
  EXPECT_TRUE(takeKernelProfile().empty());
}

TEST_F(ClRuntime, EveryEmbeddedKernelBuilds) {
  ASSERT_FALSE(embeddedKernels().empty());
  for (const KernelSource* k : embeddedKernels()) {
    EXPECT_NO_THROW(ctx().program(k->name)) << k->name;
    EXPECT_EQ(std::string(k->sha256).size(), 64u) << k->name;
  }
}

TEST_F(ClRuntime, EveryEmbeddedKernelBuildsWithWarningsAsErrors) {
  // The OpenCL build option -Werror: a warning of the device compiler fails the build.
  for (const KernelSource* k : embeddedKernels()) {
    EXPECT_NO_THROW(ctx().program(k->name, "-Werror")) << k->name;
  }
}

TEST_F(ClRuntime, IncludesAreInlinedAtEmbedTime) {
  const KernelSource* k = findEmbeddedKernel("image_scale");
  ASSERT_NE(k, nullptr);
  EXPECT_NE(std::string(k->source).find("emf_is_valid(float v)"), std::string::npos);
  EXPECT_EQ(std::string(k->source).find("#include \"common.clh\""), std::string::npos);
}

TEST(ProgramCacheTest, SecondContextLoadsFromDisk) {
  const std::string dir = test::tempDir("clcache");
  ClOptions o;
  o.cache_dir = dir;
  {
    Context first(o);
    first.program("image_scale");
    const auto s = first.cacheStats();
    EXPECT_EQ(s.compiled, 1);
    EXPECT_EQ(s.disk_hits, 0);
    EXPECT_EQ(s.stored, 1);
    first.program("image_scale");
    EXPECT_EQ(first.cacheStats().memory_hits, 1);
  }
  Context second(o);
  second.program("image_scale");
  EXPECT_EQ(second.cacheStats().disk_hits, 1);
  EXPECT_EQ(second.cacheStats().compiled, 0);
  // Different build options are a different cache entry.
  second.program("image_scale", "-DEMF_TEST_OPTION=1");
  EXPECT_EQ(second.cacheStats().compiled, 1);
  const KernelSource* k = findEmbeddedKernel("image_scale");
  EXPECT_NE(second.cacheKey(k->sha256, "-cl-std=CL1.2"),
            second.cacheKey(k->sha256, "-cl-std=CL1.2 -DX"));
}

TEST(ProgramCacheTest, CorruptEntryIsRecompiled) {
  const std::string dir = test::tempDir("clcache-corrupt");
  ClOptions o;
  o.cache_dir = dir;
  std::string path;
  {
    Context first(o);
    first.program("image_scale");
    const KernelSource* k = findEmbeddedKernel("image_scale");
    path = first.cache().pathFor(first.cacheKey(k->sha256, first.programOptions()));
  }
  ASSERT_TRUE(std::filesystem::exists(path));
  { std::ofstream(path, std::ios::trunc) << "garbage"; }
  Context second(o);
  EXPECT_NO_THROW(second.program("image_scale"));
  EXPECT_EQ(second.cacheStats().compiled, 1);
  EXPECT_EQ(second.cacheStats().stored, 1);  // repaired
}

TEST(ProgramCacheTest, UnusableCacheDirStillBuilds) {
  const std::string dir = test::tempDir("clcache-file");
  const std::string not_a_dir = dir + "/file";
  { std::ofstream(not_a_dir) << "x"; }
  ClOptions o;
  o.cache_dir = not_a_dir + "/sub";  // cannot be created: a file is in the way
  Context ctx(o);
  EXPECT_NO_THROW(ctx.program("image_scale"));
  EXPECT_EQ(ctx.cacheStats().compiled, 1);
  EXPECT_EQ(ctx.cacheStats().stored, 0);
}

TEST(ProgramCacheTest, DisabledCacheNeverTouchesDisk) {
  const std::string dir = test::tempDir("clcache-off");
  ClOptions o;
  o.cache_dir = dir;
  o.disable_cache = true;
  Context ctx(o);
  ctx.program("image_scale");
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

TEST_F(ClRuntime, BuildErrorCarriesBuildLog) {
  try {
    ctx().program("image_scale", "-DEMF_FORCE_ERROR -Dfloat=this_is_not_a_type");
    FAIL() << "expected a build failure";
  } catch (const ClError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.code(), CL_BUILD_PROGRAM_FAILURE) << what;
    EXPECT_NE(what.find("kernels_cl/image_scale.cl"), std::string::npos) << what;
    EXPECT_NE(what.find("build log:"), std::string::npos) << what;
    EXPECT_NE(what.find("this_is_not_a_type"), std::string::npos) << what;
  }
}

TEST_F(ClRuntime, UnknownKernelFileIsAClearError) {
  try {
    ctx().program("no_such_stage");
    FAIL();
  } catch (const ClError& e) {
    EXPECT_NE(std::string(e.what()).find("kernels_cl/no_such_stage.cl"), std::string::npos);
  }
}

TEST_F(ClRuntime, RaiiHandlesRetainAndRelease) {
  MemHandle a = ctx().buffer(CL_MEM_READ_WRITE, 64);
  cl_uint refs = 0;
  ASSERT_CL_SUCCESS(
      clGetMemObjectInfo(a.get(), CL_MEM_REFERENCE_COUNT, sizeof(refs), &refs, nullptr));
  EXPECT_EQ(refs, 1u);
  {
    MemHandle b = a;  // copy retains
    ASSERT_CL_SUCCESS(
        clGetMemObjectInfo(a.get(), CL_MEM_REFERENCE_COUNT, sizeof(refs), &refs, nullptr));
    EXPECT_EQ(refs, 2u);
  }
  ASSERT_CL_SUCCESS(
      clGetMemObjectInfo(a.get(), CL_MEM_REFERENCE_COUNT, sizeof(refs), &refs, nullptr));
  EXPECT_EQ(refs, 1u);
  MemHandle c = std::move(a);
  EXPECT_FALSE(a);  // NOLINT(bugprone-use-after-move): moved-from is empty by contract
  EXPECT_TRUE(c);
}

}  // namespace
}  // namespace emf::cl
