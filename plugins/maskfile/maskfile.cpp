// `maskfile` detector plugin: replays the detections stored with a dataset
// (docs/inputs_outputs.md#detections-on-disk): masks/<timestamp>.png (uint16, pixel = detection
// id 1..n, 0 = none) and masks/<timestamp>.txt (`det_id class_name score`, '_' for spaces in
// names), <timestamp> being the depth timestamp string of the frame.
//
// Config: "" (the dataset folder is taken from the source URI, tum:<dir> or cofusion:<dir>) or
// "dir=<dataset folder>". Frames without a masks file have no detections.
#include <emf/emf_detector.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace {
/// Everything one detect() result owns until release().
struct Result {
  emf_detection_result result{};
  std::vector<emf_detection> detections;
  std::vector<std::string> names;
  std::vector<std::vector<uint8_t>> masks;
};
}  // namespace

struct emf_detector {
  std::string dir;                                                // dataset folder
  std::map<emf_detection_result*, std::unique_ptr<Result>> live;  // results not yet released
};

namespace {

void setError(char* error, size_t size, const std::string& msg) {
  if (!error || size == 0) return;
  std::snprintf(error, size, "%s", msg.c_str());
}

/// %XX sequences decoded, as emf's URI parser does for the path ("my%20data" -> "my data").
std::string percentDecode(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '%' && i + 2 < text.size() &&
        std::isxdigit(static_cast<unsigned char>(text[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(text[i + 2]))) {
      out += static_cast<char>(std::stoi(text.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += text[i];
    }
  }
  return out;
}

/// The dataset folder of a tum:<dir> or cofusion:<dir> URI (scheme in any case, path
/// percent-decoded, query dropped), "" for other sources.
std::string folderFromUri(const std::string& uri) {
  for (const char* scheme : {"tum:", "cofusion:"}) {
    const size_t n = std::strlen(scheme);
    if (uri.size() < n) continue;
    bool same = true;
    for (size_t i = 0; i < n; ++i) {
      same = same && std::tolower(static_cast<unsigned char>(uri[i])) == scheme[i];
    }
    if (same) {
      const std::string rest = uri.substr(n);
      return percentDecode(rest.substr(0, rest.find('?')));
    }
  }
  return "";
}

/// The fields of a masks/<timestamp>.txt line as emf's dataset reader splits them: blanks and
/// tabs separate, a CR at the end is dropped; empty for a blank line or one whose first non-blank
/// character is '#'.
std::vector<std::string> tableFields(std::string line) {
  if (!line.empty() && line.back() == '\r') line.pop_back();
  std::vector<std::string> fields;
  std::istringstream in(line);
  for (std::string f; in >> f;) {
    if (fields.empty() && f[0] == '#') break;
    fields.push_back(f);
  }
  return fields;
}

emf_status create(const emf_detector_create_info* info, emf_detector** out, char* error,
                  size_t error_size) {
  try {
    if (!info || !out) {
      setError(error, error_size, "maskfile: NULL argument");
      return EMF_ERROR_INVALID_ARGUMENT;
    }
    std::string config = info->config ? info->config : "";
    std::string dir;
    if (config.rfind("dir=", 0) == 0) {
      dir = config.substr(4);
    } else if (!config.empty()) {
      setError(error, error_size,
               "maskfile: unknown config '" + config + "' (use \"dir=<dataset folder>\" or \"\")");
      return EMF_ERROR_CONFIG;
    } else {
      dir = folderFromUri(info->source_uri ? info->source_uri : "");
    }
    if (dir.empty()) {
      setError(error, error_size,
               "maskfile: no dataset folder: the source is not tum:<dir> or cofusion:<dir>; pass "
               "detector.plugin_config \"dir=<dataset folder>\"");
      return EMF_ERROR_CONFIG;
    }
    // A wrong folder would otherwise give a run with no detections and no word about it.
    std::error_code ec;
    if (!std::filesystem::is_directory(dir + "/masks", ec)) {
      setError(
          error, error_size,
          "maskfile: '" + dir + "/masks' is not a folder: " +
              (std::filesystem::is_directory(dir, ec) ? "the dataset holds no stored detections"
                                                      : "'" + dir + "' does not exist") +
              "; point detector.plugin_config \"dir=<dataset folder>\" (or the source) at "
              "a dataset with masks/ (emf synth writes them), or use another detector");
      return EMF_ERROR_CONFIG;
    }
    auto d = std::make_unique<emf_detector>();
    d->dir = dir;
    *out = d.release();
    return EMF_OK;
  } catch (const std::exception& e) {
    setError(error, error_size, std::string("maskfile: ") + e.what());
    return EMF_ERROR_INTERNAL;
  }
}

emf_status detect(emf_detector* det, const emf_detector_frame* frame, emf_detection_result** out,
                  char* error, size_t error_size) {
  try {
    *out = nullptr;
    const std::string stamp = frame->timestamp_text ? frame->timestamp_text : "";
    const std::string base = det->dir + "/masks/" + stamp;
    std::ifstream txt(base + ".txt");
    if (!txt) return EMF_OK;  // no detections stored for this frame
    cv::Mat ids = cv::imread(base + ".png", cv::IMREAD_UNCHANGED);
    if (ids.empty()) {
      setError(error, error_size, "maskfile: " + base + ".png is missing or unreadable");
      return EMF_ERROR_IO;
    }
    if (ids.type() != CV_16UC1) {
      setError(error, error_size, "maskfile: " + base + ".png is not a 16-bit single-channel PNG");
      return EMF_ERROR_IO;
    }
    if (ids.cols != frame->depth.width || ids.rows != frame->depth.height) {
      setError(error, error_size,
               "maskfile: " + base + ".png is " + std::to_string(ids.cols) + "x" +
                   std::to_string(ids.rows) + ", the depth image is " +
                   std::to_string(frame->depth.width) + "x" + std::to_string(frame->depth.height));
      return EMF_ERROR_IO;
    }
    auto r = std::make_unique<Result>();
    std::string line;
    int line_no = 0;
    std::map<long, int> id_lines;  // detection id -> line, to refuse an id listed twice
    while (std::getline(txt, line)) {
      ++line_no;
      const std::vector<std::string> fields = tableFields(line);
      if (fields.empty()) continue;
      const std::string where = "maskfile: " + base + ".txt:" + std::to_string(line_no) + ": ";
      // strtol / strtod: no undefined behaviour on out-of-range text (sscanf's %d has it).
      char* id_end = nullptr;
      char* score_end = nullptr;
      const long id = fields.size() == 3 ? std::strtol(fields[0].c_str(), &id_end, 10) : 0;
      const double score = fields.size() == 3 ? std::strtod(fields[2].c_str(), &score_end) : -1;
      if (fields.size() != 3 || *id_end != '\0' || *score_end != '\0' || id <= 0 || id > 65535 ||
          !std::isfinite(score) || score < 0.0 || score > 1.0) {
        setError(error, error_size,
                 where +
                     "expected `det_id class_name score` (id 1..65535, score in [0, 1]), got '" +
                     line + "'");
        return EMF_ERROR_IO;
      }
      if (!id_lines.emplace(id, line_no).second) {
        setError(error, error_size,
                 where + "detection id " + fields[0] + " is listed twice (also on line " +
                     std::to_string(id_lines[id]) + ")");
        return EMF_ERROR_IO;
      }
      std::string name = fields[1];
      for (char& c : name) c = (c == '_') ? ' ' : c;
      std::vector<uint8_t> mask(static_cast<size_t>(ids.total()), 0);
      int x0 = ids.cols, y0 = ids.rows, x1 = -1, y1 = -1;
      for (int y = 0; y < ids.rows; ++y) {
        const uint16_t* row = ids.ptr<uint16_t>(y);
        for (int x = 0; x < ids.cols; ++x) {
          if (row[x] != id) continue;
          mask[static_cast<size_t>(y) * ids.cols + x] = 1;
          x0 = std::min(x0, x);
          y0 = std::min(y0, y);
          x1 = std::max(x1, x);
          y1 = std::max(y1, y);
        }
      }
      if (x1 < 0) continue;  // listed but no pixels (e.g. cropped away): nothing to report
      r->names.push_back(name);
      r->masks.push_back(std::move(mask));
      emf_detection d{};
      d.struct_size = sizeof(d);
      d.score = static_cast<float>(score);
      d.box_x = x0;
      d.box_y = y0;
      d.box_width = x1 - x0 + 1;
      d.box_height = y1 - y0 + 1;
      d.mask_width = ids.cols;
      d.mask_height = ids.rows;
      r->detections.push_back(d);
    }
    for (size_t i = 0; i < r->detections.size(); ++i) {
      r->detections[i].class_name = r->names[i].c_str();
      r->detections[i].mask = r->masks[i].data();
    }
    r->result.struct_size = sizeof(r->result);
    r->result.count = static_cast<int32_t>(r->detections.size());
    r->result.detections = r->detections.data();
    emf_detection_result* handle = &r->result;
    det->live.emplace(handle, std::move(r));
    *out = handle;
    return EMF_OK;
  } catch (const std::exception& e) {
    setError(error, error_size, std::string("maskfile: ") + e.what());
    return EMF_ERROR_INTERNAL;
  }
}

void release(emf_detector* det, emf_detection_result* result) {
  if (det && result) det->live.erase(result);
}

void destroy(emf_detector* det) { delete det; }

const emf_detector_api kApi = {sizeof(emf_detector_api),
                               EMF_DETECTOR_ABI_VERSION,
                               "maskfile",
                               "replays masks/<timestamp>.png + .txt stored with a dataset",
                               create,
                               detect,
                               release,
                               destroy,
                               0u};

}  // namespace

extern "C" EMF_DETECTOR_EXPORT const emf_detector_api* emf_detector_entry(uint32_t host_abi) {
  return host_abi == EMF_DETECTOR_ABI_VERSION ? &kApi : nullptr;
}
