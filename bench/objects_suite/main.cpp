// objects_suite: the object figures over many generated scenes (synth:random) at once, with
// configurations side by side in one run. Every seed's frames are rendered once and fed to
// every configuration in lock step (the simulated detector's results go in as a maskfile
// replay would give them). Prints per seed the camera ATE and, per ground-truth object, the
// matched estimate's ATE and coverage and how many estimates the object was split into, then
// median / p90 / worst over seeds and objects, and one machine-readable line per
// configuration. Scoring: objects_suite/scoring.h.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string>
#include <vector>

#include "bench_args.h"
#include "cl/context.h"
#include "common/error.h"
#include "common/log.h"
#include "map/raycaster.h"
#include "objects_suite/scoring.h"
#include "pipeline/config.h"
#include "pipeline/slam_system.h"
#include "synth/scene.h"
#include "synth/synth_source.h"

namespace {

using emf::bench::ObjectScore;
using emf::bench::quantile;
using emf::bench::RunRecord;
using emf::bench::RunScore;

const char* kUsage =
    "usage: objects_suite [--seeds N] [--first-seed S] [--seed-list A,B,..] [--size WxH]\n"
    "                     [--frames N] [--scene QUERY] [--config FILE] [--set KEY=VALUE]...\n"
    "                     [--vs KEY=VALUE]... [--paper] [--paper-config FILE] [--json FILE]\n"
    "                     [--per-seed]\n"
    "  Runs emf on the generated scenes synth:random?seed=S (seeds S = first-seed .. + N - 1,\n"
    "  or the list) and scores the objects against the ground truth.\n"
    "  --seeds N         scenes (default 16 at 320x240 and below, 6 above)\n"
    "  --size WxH        image size (default 320x240); the background is 10.24 m across,\n"
    "                    centred on the first camera, at 2 cm (320 and below) or 1 cm\n"
    "  --frames N        frames per scene (default 600)\n"
    "  --scene QUERY     more synth:random query keys, e.g. 'movers=2&camera=orbit'\n"
    "  --config, --set   the configuration under test ('default' column)\n"
    "  --vs KEY=VALUE[,KEY=VALUE..]  adds a column: that configuration with these keys\n"
    "                    changed (repeat for more columns)\n"
    "  --paper           adds a column: the paper's values (conf/paper.yaml, or --paper-config)\n"
    "  --json FILE       every seed's scores as JSON lines\n"
    "  --per-seed        print every seed's objects (default: only the summary per seed)\n";

struct Args {
  int seeds = 0;
  uint64_t first_seed = 1;
  std::vector<uint64_t> seed_list;
  int width = 320, height = 240, frames = 600;
  std::string scene_query, config_file, json, paper_config = EMF_SOURCE_DIR "/conf/paper.yaml";
  std::vector<std::string> sets, vs;
  bool paper = false, per_seed = false;
};

Args parse(int argc, char** argv) {
  Args a;
  emf::bench::ArgWalker w(argc, argv);
  while (w.next()) {
    if (w.is("--seeds")) {
      a.seeds = static_cast<int>(w.integer(1, 10000));
    } else if (w.is("--first-seed")) {
      a.first_seed = static_cast<uint64_t>(w.integer(0, 1000000000));
    } else if (w.is("--seed-list")) {
      const std::string list = w.value();
      size_t pos = 0;
      while (pos <= list.size()) {
        const size_t comma = std::min(list.find(',', pos), list.size());
        a.seed_list.push_back(static_cast<uint64_t>(
            emf::bench::parseInteger("--seed-list", list.substr(pos, comma - pos), 0, 1000000000)));
        pos = comma + 1;
      }
    } else if (w.is("--size")) {
      const std::string s = w.value();
      const size_t x = s.find('x');
      if (x == std::string::npos) throw emf::bench::UsageError("--size '" + s + "': expected WxH");
      a.width = static_cast<int>(emf::bench::parseInteger("--size", s.substr(0, x), 16, 4096));
      a.height = static_cast<int>(emf::bench::parseInteger("--size", s.substr(x + 1), 16, 4096));
    } else if (w.is("--frames")) {
      a.frames = static_cast<int>(w.integer(30, 100000));
    } else if (w.is("--scene")) {
      a.scene_query = w.value();
    } else if (w.is("--config")) {
      a.config_file = w.value();
    } else if (w.is("--set")) {
      a.sets.push_back(w.value());
    } else if (w.is("--vs")) {
      a.vs.push_back(w.value());
    } else if (w.is("--paper")) {
      a.paper = true;
    } else if (w.is("--paper-config")) {
      a.paper_config = w.value();
      a.paper = true;
    } else if (w.is("--json")) {
      a.json = w.value();
    } else if (w.is("--per-seed")) {
      a.per_seed = true;
    } else if (w.is("-h") || w.is("--help")) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else {
      w.unknown();
    }
  }
  if (a.seeds == 0) a.seeds = a.width <= 320 ? 16 : 6;
  if (a.seed_list.empty()) {
    for (int i = 0; i < a.seeds; ++i)
      a.seed_list.push_back(a.first_seed + static_cast<uint64_t>(i));
  }
  return a;
}

struct Variant {
  std::string name;
  emf::Config config;
};

/// The background for the generated rooms, in every configuration compared: 10.24 m across
/// with the first camera at its centre (an orbiting camera sees the walls behind its start,
/// which the default 5.12 m volume ahead of it leaves out), 2 cm voxels at 320 px and below (as
/// the tests and bench/objects_bench.sh), 1 cm above.
void sizeDefaults(emf::Config* c, int width) {
  c->map.initial_camera_face_offset = 0.0;
  if (width <= 320) {
    c->map.background_voxel_m = 0.02f;
    c->map.background_resolution = 512;
  } else {
    c->map.background_voxel_m = 0.01f;
    c->map.background_resolution = 1024;
  }
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw emf::IoError(path + ": cannot read the configuration file");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<Variant> variants(const Args& a) {
  std::vector<Variant> out;
  emf::Config base;
  sizeDefaults(&base, a.width);
  if (!a.config_file.empty()) base.merge(readText(a.config_file), a.config_file);
  for (const auto& s : a.sets) base.set(s);
  base.validate();
  out.push_back({"default", base});
  // Each --vs is a column: the configuration under test with its comma-separated keys changed.
  for (const auto& column : a.vs) {
    emf::Config v = base;
    size_t pos = 0;
    while (pos <= column.size()) {
      const size_t comma = std::min(column.find(',', pos), column.size());
      v.set(column.substr(pos, comma - pos));
      pos = comma + 1;
    }
    v.validate();
    out.push_back({column, v});
  }
  if (a.paper) {
    emf::Config p;
    sizeDefaults(&p, a.width);
    p.merge(readText(a.paper_config), a.paper_config);
    p.validate();
    out.push_back({"paper", p});
  }
  return out;
}

std::map<std::string, std::string> parseQuery(const std::string& q) {
  std::map<std::string, std::string> m;
  size_t pos = 0;
  while (pos < q.size()) {
    const size_t amp = std::min(q.find('&', pos), q.size());
    const std::string item = q.substr(pos, amp - pos);
    const size_t eq = item.find('=');
    if (eq == std::string::npos) {
      throw emf::bench::UsageError("--scene '" + q + "': '" + item + "' is not KEY=VALUE");
    }
    m[item.substr(0, eq)] = item.substr(eq + 1);
    pos = amp + 1;
  }
  return m;
}

/// One configuration's run of one scene, frame by frame.
struct Runner {
  emf::pipeline::SlamSystem slam;
  // The estimates' masks for their labels: the map ray-cast at 320 px wide at most.
  emf::core::Intrinsics label_k;
  emf::map::RayCaster label_caster;
  RunRecord record;
  std::map<int, size_t> est_index;  // estimated id -> index in record.est

  static emf::core::Intrinsics labelIntrinsics(const emf::core::Intrinsics& k) {
    if (k.width <= 320) return k;
    return k.scaled(320, static_cast<int>(std::lround(k.height * 320.0 / k.width)));
  }

  Runner(emf::cl::Context& ctx, const emf::Config& config, const emf::core::Intrinsics& k)
      : slam(ctx, config, k),
        label_k(labelIntrinsics(k)),
        label_caster(ctx, config.map, label_k.width, label_k.height) {}

  void process(const emf::core::Frame& frame, size_t f) {
    const auto t0 = std::chrono::steady_clock::now();
    const emf::pipeline::FrameOutcome out =
        slam.process(frame, frame.detections ? &*frame.detections : nullptr);
    record.ms_per_frame.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    record.T_world_camera.push_back(
        out.lost ? std::nullopt : std::optional<Eigen::Isometry3d>(out.T_world_camera));
    cv::Mat rendered, truth;
    const bool any_tracked = std::any_of(out.objects.begin(), out.objects.end(), [](const auto& o) {
      return o.state == emf::pipeline::ObjectState::kTracked;
    });
    if (any_tracked) {
      label_caster.render(slam.renderItems(), label_k, out.T_world_camera);
      label_caster.download(nullptr, nullptr, &rendered);
      cv::resize(frame.instance_ids, truth, rendered.size(), 0, 0, cv::INTER_NEAREST);
    }
    // Objects confirmed now (objects.confirm_detections): their frames since creation first.
    for (const auto& c : out.confirmed) {
      auto it = est_index.emplace(c.id, record.est.size()).first;
      if (it->second == record.est.size()) {
        record.est.emplace_back();
        record.est.back().id = c.id;
        record.est.back().class_name = c.class_name;
      }
      emf::bench::EstObject& e = record.est[it->second];
      for (const auto& p : c.earlier) {
        e.frames.push_back(p.index);
        e.T_object_camera.push_back(p.T_object_camera);
        e.labels.push_back(-1);  // no mask of those frames: no vote
      }
    }
    for (const auto& o : out.objects) {
      auto it = est_index.find(o.id);
      if (it == est_index.end()) {
        it = est_index.emplace(o.id, record.est.size()).first;
        record.est.emplace_back();
        record.est.back().id = o.id;
        record.est.back().class_name = o.class_name;
      }
      emf::bench::EstObject& e = record.est[it->second];
      if (o.state == emf::pipeline::ObjectState::kLost) ++e.lost_frames;
      if (o.state != emf::pipeline::ObjectState::kTracked) continue;
      e.frames.push_back(static_cast<int64_t>(f));
      e.T_object_camera.push_back(o.T_object_camera);
      e.labels.push_back(emf::bench::labelFromMasks(rendered, truth, o.id));
    }
  }
};

std::string cm(const std::optional<double>& m) {
  if (!m) return "-";
  char b[32];
  std::snprintf(b, sizeof(b), "%.2f", *m * 100.0);
  return b;
}

std::string num(double v, const char* fmt) {
  if (!std::isfinite(v)) return "-";
  char b[32];
  std::snprintf(b, sizeof(b), fmt, v);
  return b;
}

/// Everything a configuration gathered over the seeds.
/// One motion family's moving objects (the first family of each object's motion).
struct FamilyTotals {
  std::vector<double> ate_cm, coverage, estimates;
};

struct Totals {
  std::map<std::string, FamilyTotals> families;
  // Per counted object in a fixed order (the same in every column): ATE (cm, inf = none) and
  // coverage (%), for the paired comparison with the first column.
  std::vector<double> paired_ate_cm, paired_coverage, paired_estimates;
  std::vector<double> camera_ate_cm, moving_ate_cm, moving_coverage, moving_union_coverage;
  std::vector<double> estimates_per_object, spurious, lost_frames, ms, ms_p90;
  int recreated_in_view = 0, id_switches = 0, still_split = 0, objects = 0, moving = 0;

  void add(const RunScore& s) {
    camera_ate_cm.push_back(s.camera_ate_m ? *s.camera_ate_m * 100 : INFINITY);
    for (const ObjectScore& o : s.objects) {
      if (o.visible_frames < 60) continue;  // too briefly in view to count
      ++objects;
      estimates_per_object.push_back(o.estimates);
      paired_ate_cm.push_back(o.ate_m ? *o.ate_m * 100 : INFINITY);
      paired_coverage.push_back(o.coverage * 100);
      paired_estimates.push_back(o.estimates);
      recreated_in_view += o.recreated_in_view;
      if (o.moving) {
        ++moving;
        moving_ate_cm.push_back(o.ate_m ? *o.ate_m * 100 : INFINITY);
        moving_coverage.push_back(o.coverage * 100);
        moving_union_coverage.push_back(o.union_coverage * 100);
        FamilyTotals& f = families[o.motion.substr(0, o.motion.find('+'))];
        f.ate_cm.push_back(moving_ate_cm.back());
        f.coverage.push_back(o.coverage * 100);
        f.estimates.push_back(o.estimates);
      } else if (o.estimates > 1) {
        ++still_split;
      }
    }
    spurious.push_back(static_cast<double>(s.spurious_ids.size()));
    id_switches += s.id_switches;
    lost_frames.push_back(static_cast<double>(s.lost_object_frames));
    ms.push_back(s.ms_median);
    ms_p90.push_back(s.ms_p90);
  }
};

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

double worstLow(const std::vector<double>& v) { return v.empty() ? 0.0 : quantile(v, 0.0); }
double worstHigh(const std::vector<double>& v) { return v.empty() ? 0.0 : quantile(v, 1.0); }

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parse(argc, argv);
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "objects_suite: %s\n%s", e.what(), kUsage);
    return emf::bench::kExitUsage;
  }
  try {
    const std::vector<Variant> configs = variants(args);
    emf::cl::Context ctx(configs[0].config.cl);
    std::unique_ptr<std::ofstream> json;
    if (!args.json.empty()) {
      json = std::make_unique<std::ofstream>(args.json);
      if (!*json) throw emf::IoError("--json " + args.json + ": cannot write the file");
    }
    std::printf("objects_suite: %zu seeds of synth:random%s%s at %dx%d, %d frames; device %s\n",
                args.seed_list.size(), args.scene_query.empty() ? "" : "?",
                args.scene_query.c_str(), args.width, args.height, args.frames,
                ctx.describe().c_str());
    std::printf("columns:");
    for (size_t c = 0; c < configs.size(); ++c) {
      std::printf(" [%zu] %s", c, configs[c].name.c_str());
    }
    std::printf("\n\n");
    std::vector<Totals> totals(configs.size());
    for (uint64_t seed : args.seed_list) {
      std::map<std::string, std::string> q = parseQuery(args.scene_query);
      q["seed"] = std::to_string(seed);
      q["frames"] = std::to_string(args.frames);
      q["width"] = std::to_string(args.width);
      q["height"] = std::to_string(args.height);
      emf::synth::SynthSource source(
          emf::synth::synthOptionsFromQuery("random", q, emf::core::SourceOptions{}));
      const emf::synth::Scene& scene = source.scene();
      std::vector<std::unique_ptr<Runner>> runners;
      for (const auto& v : configs) {
        runners.push_back(std::make_unique<Runner>(ctx, v.config, source.intrinsics()));
      }
      // Ground truth, shared by the runs.
      std::vector<emf::bench::GtObject> gt;
      for (const auto& o : scene.objects) {
        emf::bench::GtObject g;
        g.id = o.id;
        g.class_name = o.class_name;
        g.motion = o.motion;
        g.bounds = emf::synth::objectBounds(o);
        gt.push_back(g);
      }
      std::vector<double> stamps;
      std::vector<Eigen::Isometry3d> cam_gt;
      const int min_px = emf::synth::minVisiblePixels(args.width, args.height);
      emf::core::Frame frame;
      size_t f = 0;
      while (source.next(frame)) {
        stamps.push_back(frame.timestamp);
        cam_gt.push_back(*frame.T_world_camera_gt);
        const std::vector<int> counts = emf::synth::instancePixelCounts(frame.instance_ids);
        for (auto& g : gt) {
          g.T_world_object.push_back(frame.T_world_object_gt.at(g.id));
          const size_t id = static_cast<size_t>(g.id);
          g.visible.push_back(id < counts.size() && counts[id] >= min_px);
        }
        for (auto& r : runners) r->process(frame, f);
        ++f;
      }
      std::printf("seed %llu: %s\n", static_cast<unsigned long long>(seed),
                  scene.description.c_str());
      std::vector<RunScore> scores;
      for (size_t c = 0; c < configs.size(); ++c) {
        RunRecord& rec = runners[c]->record;
        rec.stamps = stamps;
        rec.T_world_camera_gt = cam_gt;
        rec.gt = gt;
        scores.push_back(emf::bench::scoreRun(rec));
        totals[c].add(scores.back());
      }
      for (size_t c = 0; c < configs.size(); ++c) {
        const RunScore& s = scores[c];
        std::string objects;
        for (const auto& o : s.objects) {
          objects += " " + std::to_string(o.gt_id) + ":" + (o.moving ? "" : "still:") +
                     cm(o.ate_m) + "cm/" + num(o.coverage * 100, "%.0f") + "%/x" +
                     std::to_string(o.estimates);
        }
        std::printf("  [%zu] camera %s cm, spurious %zu, lost object frames %lld, %.1f ms |%s\n", c,
                    cm(s.camera_ate_m).c_str(), s.spurious_ids.size(),
                    static_cast<long long>(s.lost_object_frames), s.ms_median, objects.c_str());
      }
      if (args.per_seed) {
        for (const auto& o : scores[0].objects) {
          std::printf("      object %d \"%s\" %s: visible %d frames\n", o.gt_id,
                      o.class_name.c_str(), o.motion.c_str(), o.visible_frames);
        }
      }
      std::fflush(stdout);
      if (json) {
        for (size_t c = 0; c < configs.size(); ++c) {
          const RunScore& s = scores[c];
          nlohmann::json j;
          j["config"] = configs[c].name;
          j["seed"] = seed;
          j["camera_ate_m"] = s.camera_ate_m ? nlohmann::json(*s.camera_ate_m) : nlohmann::json();
          j["spurious"] = s.spurious_ids;
          for (const auto& e : runners[c]->record.est) {
            if (std::find(s.spurious_ids.begin(), s.spurious_ids.end(), e.id) ==
                s.spurious_ids.end()) {
              continue;
            }
            j["spurious_detail"].push_back({{"id", e.id},
                                            {"class", e.class_name},
                                            {"first_frame", e.frames.front()},
                                            {"tracked_frames", e.frames.size()}});
          }
          j["id_switches"] = s.id_switches;
          j["lost_object_frames"] = s.lost_object_frames;
          j["ms_median"] = s.ms_median;
          for (const auto& o : s.objects) {
            j["objects"].push_back(
                {{"id", o.gt_id},
                 {"class", o.class_name},
                 {"motion", o.motion},
                 {"moving", o.moving},
                 {"visible", o.visible_frames},
                 {"estimates", o.estimates},
                 {"recreated_in_view", o.recreated_in_view},
                 {"ate_m", o.ate_m ? nlohmann::json(*o.ate_m) : nlohmann::json()},
                 {"coverage", o.coverage},
                 {"union_coverage", o.union_coverage}});
          }
          *json << j.dump() << "\n";
        }
        json->flush();
      }
    }

    std::printf("\nsummary over %zu seeds (%dx%d, %d frames): median / p90 [worst]\n",
                args.seed_list.size(), args.width, args.height, args.frames);
    auto row = [&](const char* label, auto cell) {
      std::printf("  %-34s", label);
      for (size_t c = 0; c < configs.size(); ++c) std::printf(" | %-24s", cell(totals[c]).c_str());
      std::printf("\n");
    };
    auto mpw = [](const std::vector<double>& v, const char* fmt, bool high_is_bad) {
      return num(quantile(v, 0.5), fmt) + " / " + num(quantile(v, high_is_bad ? 0.9 : 0.1), fmt) +
             " [" + num(high_is_bad ? worstHigh(v) : worstLow(v), fmt) + "]";
    };
    for (size_t c = 0; c < configs.size(); ++c)
      std::printf("  [%zu] %s\n", c, configs[c].name.c_str());
    row("camera ATE, cm", [&](const Totals& t) { return mpw(t.camera_ate_cm, "%.2f", true); });
    row("moving objects: ATE, cm",
        [&](const Totals& t) { return mpw(t.moving_ate_cm, "%.2f", true); });
    row("moving objects: coverage, % (p10)",
        [&](const Totals& t) { return mpw(t.moving_coverage, "%.0f", false); });
    row("moving objects: any estimate, %",
        [&](const Totals& t) { return mpw(t.moving_union_coverage, "%.0f", false); });
    row("estimates per object: mean [worst]", [&](const Totals& t) {
      return num(mean(t.estimates_per_object), "%.2f") + " [" +
             num(worstHigh(t.estimates_per_object), "%.0f") + "]";
    });
    row("re-created in view / still split", [&](const Totals& t) {
      return std::to_string(t.recreated_in_view) + " / " + std::to_string(t.still_split);
    });
    row("spurious per sequence", [&](const Totals& t) { return mpw(t.spurious, "%.0f", true); });
    row("id switches (total)", [&](const Totals& t) { return std::to_string(t.id_switches); });
    row("lost object frames per sequence",
        [&](const Totals& t) { return mpw(t.lost_frames, "%.0f", true); });
    row("ms per frame (median of runs)", [&](const Totals& t) { return mpw(t.ms, "%.1f", true); });
    row("objects counted (moving)", [&](const Totals& t) {
      return std::to_string(t.objects) + " (" + std::to_string(t.moving) + ")";
    });
    // Paired with the first column, object by object: how many got better or worse (ATE by
    // more than 10 % and 0.2 cm, coverage by more than 5 points, estimates by one or more).
    if (configs.size() > 1) {
      std::printf("\npaired with [0] (objects better / worse): ATE, coverage, estimates\n");
      for (size_t c = 1; c < configs.size(); ++c) {
        int ate_b = 0, ate_w = 0, cov_b = 0, cov_w = 0, est_b = 0, est_w = 0;
        const Totals& a = totals[0];
        const Totals& b = totals[c];
        for (size_t i = 0; i < a.paired_ate_cm.size() && i < b.paired_ate_cm.size(); ++i) {
          const double x = a.paired_ate_cm[i], y = b.paired_ate_cm[i];
          if (y < x && (std::isinf(x) || (x - y > 0.1 * x && x - y > 0.2))) ++ate_b;
          if (x < y && (std::isinf(y) || (y - x > 0.1 * x && y - x > 0.2))) ++ate_w;
          if (b.paired_coverage[i] > a.paired_coverage[i] + 5) ++cov_b;
          if (b.paired_coverage[i] < a.paired_coverage[i] - 5) ++cov_w;
          if (b.paired_estimates[i] < a.paired_estimates[i]) ++est_b;
          if (b.paired_estimates[i] > a.paired_estimates[i]) ++est_w;
        }
        std::printf("  [%zu] %s: ATE %d / %d, coverage %d / %d, estimates %d / %d\n", c,
                    configs[c].name.c_str(), ate_b, ate_w, cov_b, cov_w, est_b, est_w);
      }
    }
    // Per motion family, over the moving objects of all seeds.
    std::set<std::string> family_names;
    for (const auto& t : totals) {
      for (const auto& [name, f] : t.families) family_names.insert(name);
    }
    std::printf(
        "\nper motion family: objects, ATE cm median [worst], coverage %% median, "
        "estimates mean\n");
    for (const auto& name : family_names) {
      std::printf("  %-8s", name.c_str());
      for (size_t c = 0; c < configs.size(); ++c) {
        const auto it = totals[c].families.find(name);
        if (it == totals[c].families.end()) {
          std::printf(" | %-36s", "-");
          continue;
        }
        const FamilyTotals& f = it->second;
        char cell[96];
        std::snprintf(
            cell, sizeof(cell), "%2zu: %s [%s] %s%% x%s", f.ate_cm.size(),
            num(quantile(f.ate_cm, 0.5), "%.2f").c_str(), num(worstHigh(f.ate_cm), "%.1f").c_str(),
            num(quantile(f.coverage, 0.5), "%.0f").c_str(), num(mean(f.estimates), "%.2f").c_str());
        std::printf(" | %-36s", cell);
      }
      std::printf("\n");
    }
    for (size_t c = 0; c < configs.size(); ++c) {
      const Totals& t = totals[c];
      std::printf(
          "objects_suite config=%s size=%dx%d seeds=%zu frames=%d camera_ate_cm=%s/%s/%s "
          "object_ate_cm=%s/%s/%s coverage_pct=%s/%s estimates_per_object=%s/%s "
          "recreated_in_view=%d spurious=%s/%s id_switches=%d lost_object_frames=%s ms=%s\n",
          configs[c].name.c_str(), args.width, args.height, args.seed_list.size(), args.frames,
          num(quantile(t.camera_ate_cm, 0.5), "%.3f").c_str(),
          num(quantile(t.camera_ate_cm, 0.9), "%.3f").c_str(),
          num(worstHigh(t.camera_ate_cm), "%.3f").c_str(),
          num(quantile(t.moving_ate_cm, 0.5), "%.3f").c_str(),
          num(quantile(t.moving_ate_cm, 0.9), "%.3f").c_str(),
          num(worstHigh(t.moving_ate_cm), "%.3f").c_str(),
          num(quantile(t.moving_coverage, 0.5), "%.1f").c_str(),
          num(worstLow(t.moving_coverage), "%.1f").c_str(),
          num(mean(t.estimates_per_object), "%.3f").c_str(),
          num(worstHigh(t.estimates_per_object), "%.0f").c_str(), t.recreated_in_view,
          num(quantile(t.spurious, 0.5), "%.1f").c_str(),
          num(worstHigh(t.spurious), "%.0f").c_str(), t.id_switches,
          num(quantile(t.lost_frames, 0.5), "%.0f").c_str(),
          num(quantile(t.ms, 0.5), "%.1f").c_str());
    }
    return 0;
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "objects_suite: %s\n%s", e.what(), kUsage);
    return emf::bench::kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "objects_suite: %s\n", e.what());
    return 1;
  }
}
