// The whole configuration of an emf system: one options struct per module, loaded from YAML
// (conf/*.yaml) and validated once. Keys not present in a file keep their defaults, so a preset
// only lists what it changes.
#pragma once

#include <string>
#include <vector>

#include "cl/cl_options.h"
#include "common/option_binder.h"
#include "core/source_options.h"
#include "em/em_options.h"
#include "map/map_options.h"
#include "pipeline/pipeline_options.h"
#include "track/track_options.h"

namespace emf {

struct Config {
  cl::ClOptions cl;
  core::SourceOptions source;
  track::PreprocessOptions preprocess;
  map::MapOptions map;
  track::TrackOptions track;
  em::EmOptions em;
  em::ObjectOptions objects;
  pipeline::DetectorOptions detector;
  pipeline::RuntimeOptions runtime;
  pipeline::OutputOptions output;

  /// Calls f(section_name, options) for every section, in file order.
  template <typename F>
  void forEachSection(F&& f) {
    f("cl", cl);
    f("source", source);
    f("preprocess", preprocess);
    f("map", map);
    f("track", track);
    f("em", em);
    f("objects", objects);
    f("detector", detector);
    f("runtime", runtime);
    f("output", output);
  }

  /// Loads a YAML file on top of the defaults. Throws ConfigError naming the file, line and key
  /// for unknown keys (with the closest valid key), wrong types and out-of-range values.
  static Config loadFile(const std::string& path);
  /// Same from YAML text; `origin` names it in errors (e.g. "<C API config_yaml>").
  static Config loadString(const std::string& yaml, const std::string& origin);
  /// Applies YAML text on top of this configuration (same checks as loading).
  void merge(const std::string& yaml, const std::string& origin);
  /// Applies one "section.key=value" override (the CLI's --set). Throws ConfigError.
  void set(const std::string& assignment);
  /// Checks every value against its range; throws ConfigError naming the key. Loading already
  /// validates; call this after changing fields programmatically.
  void validate() const;
  /// The configuration as YAML text (every key, current values).
  std::string toYaml() const;
};

/// One documented key, as declared by a module's bind().
struct OptionInfo {
  std::string section;
  std::string key;
  std::string type;   // real, integer, boolean, text, choice, list
  std::string range;  // "[lo, hi]" or "a|b|c" or ""
  std::string unit;
  std::string doc;
  std::string default_value;  // as YAML scalar text
};

/// Every key of every section with its default, unit and range.
std::vector<OptionInfo> listOptions();

/// Edit distance used to suggest the closest valid key (exposed for tests).
int editDistance(const std::string& a, const std::string& b);

}  // namespace emf
