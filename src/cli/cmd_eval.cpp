// `emf eval`: ATE/RPE of the camera and every ground-truth object, as a table, eval.json and
// eval.png.
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "cli/arg_parser.h"
#include "cli/commands.h"
#include "common/error.h"
#include "eval/eval.h"
#include "io/atomic_output.h"

namespace emf::cli {
namespace {

// A number in [0, 1e6) (`zero_ok`) or (0, 1e6): a zero time delta or association threshold
// would give empty or all-zero figures instead of an error.
double parseNumber(const std::string& text, const char* flag, bool zero_ok) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(zero_ok ? v >= 0 : v > 0) || !(v < 1e6)) {
    throw InvalidArgument(std::string("--") + flag + " must be a " +
                          (zero_ok ? "non-negative" : "positive") + " number, got '" + text + "'");
  }
  return v;
}

}  // namespace

int cmdEval(const std::vector<std::string>& args) {
  std::string gt, est, out_dir, max_diff = "0.02", delta = "1", min_coverage = "0.3";
  bool no_files = false;
  ArgParser p("eval",
              "Evaluates trajectories like the TUM RGB-D tools: ATE (timestamps associated "
              "within --max-diff, rigid Horn alignment, RMSE/mean/median/max) and RPE (fixed "
              "delta, translational and rotational RMSE) for the camera and for every "
              "ground-truth object (objects/gt-object-<k>-camera.txt), matched one to one to "
              "the estimated object-<id>.txt files that cover at least --min-coverage of its "
              "timestamps, pairs of lowest ATE first. Prints a table and writes eval.json and "
              "eval.png.");
  p.option("gt", &gt, "PATH", "dataset folder (groundtruth.txt, objects/) or trajectory file");
  p.option("est", &est, "PATH", "emf output folder (camera.txt, object-<id>.txt) or file");
  p.option("out", &out_dir, "DIR", "where eval.json and eval.png go (default: --est folder)");
  p.option("max-diff", &max_diff, "S", "timestamp association threshold in s (default 0.02)");
  p.option("delta", &delta, "S", "RPE time delta in s (default 1)");
  p.option("min-coverage", &min_coverage, "F",
           "fraction of a GT object's timestamps an estimate must cover (default 0.3)");
  p.flag("no-files", &no_files, "only print the table");
  if (auto code = p.parse(args)) return *code;
  if (gt.empty() || est.empty()) {
    std::fprintf(stderr, "emf eval: --gt and --est are required\n\n%s", p.usage().c_str());
    return kExitUsage;
  }
  eval::EvalOptions options;
  options.max_diff_s = parseNumber(max_diff, "max-diff", false);
  options.rpe_delta_s = parseNumber(delta, "delta", false);
  options.min_object_coverage = parseNumber(min_coverage, "min-coverage", true);
  if (options.min_object_coverage > 1.0) {
    throw InvalidArgument("--min-coverage is a fraction of the timestamps in [0, 1], got '" +
                          min_coverage + "'");
  }

  const eval::EvalReport report = eval::evaluatePaths(gt, est, options);
  std::printf("%s", eval::formatReport(report).c_str());

  if (no_files) return kExitOk;
  if (out_dir.empty()) {
    if (!std::filesystem::is_directory(est)) {
      std::fprintf(stderr,
                   "emf eval: --est is a file: pass --out DIR to write eval.json and "
                   "eval.png\n");
      return kExitOk;
    }
    out_dir = est;
  }
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw IoError("cannot create output folder '" + out_dir + "': " + ec.message());
  const std::string json_path = (std::filesystem::path(out_dir) / "eval.json").string();
  const std::string png_path = (std::filesystem::path(out_dir) / "eval.png").string();
  io::writeFileAtomically(json_path, eval::reportToJson(report).dump(2) + "\n");
  eval::writeEvalPlot(png_path, report);
  std::printf("wrote %s and %s\n", json_path.c_str(), png_path.c_str());
  return kExitOk;
}

}  // namespace emf::cli
