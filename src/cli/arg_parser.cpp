#include "cli/arg_parser.h"

#include <cstdio>
#include <sstream>

#include "pipeline/config.h"

namespace emf::cli {

ArgParser::ArgParser(std::string command, std::string summary)
    : command_(std::move(command)), summary_(std::move(summary)) {}

void ArgParser::flag(const std::string& name, bool* value, const std::string& help) {
  opts_.push_back({name, "", help, value, nullptr, nullptr});
}
void ArgParser::option(const std::string& name, std::string* value, const std::string& meta,
                       const std::string& help) {
  opts_.push_back({name, meta, help, nullptr, value, nullptr});
}
void ArgParser::repeated(const std::string& name, std::vector<std::string>* values,
                         const std::string& meta, const std::string& help) {
  opts_.push_back({name, meta, help, nullptr, nullptr, values});
}
void ArgParser::positional(const std::string& name, std::string* value, const std::string& help,
                           bool required) {
  pos_.push_back({name, help, value, required});
}

const ArgParser::Opt* ArgParser::find(const std::string& name) const {
  for (const auto& o : opts_) {
    if (o.name == name) return &o;
  }
  return nullptr;
}

std::string ArgParser::usage() const {
  std::ostringstream os;
  os << "usage: emf " << command_ << " [options]";
  for (const auto& p : pos_) os << (p.required ? " <" : " [") << p.name << (p.required ? ">" : "]");
  os << "\n\n" << summary_ << "\n";
  if (!pos_.empty()) {
    os << "\narguments:\n";
    for (const auto& p : pos_) {
      std::string head = "  " + p.name;
      os << head << std::string(head.size() < 26 ? 26 - head.size() : 1, ' ') << p.help << "\n";
    }
  }
  os << "\noptions:\n";
  for (const auto& o : opts_) {
    std::string head = "  --" + o.name + (o.meta.empty() ? "" : " " + o.meta);
    os << head << std::string(head.size() < 26 ? 26 - head.size() : 1, ' ') << o.help
       << (o.values ? " (repeatable)" : "") << "\n";
  }
  os << "  --help                  show this help\n";
  return os.str();
}

std::optional<int> ArgParser::parse(const std::vector<std::string>& args) {
  auto usageError = [&](const std::string& msg) {
    std::fprintf(stderr, "emf %s: %s\n\n%s", command_.c_str(), msg.c_str(), usage().c_str());
    return std::optional<int>(kExitUsage);
  };
  size_t next_pos = 0;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") {
      std::printf("%s", usage().c_str());
      return kExitOk;
    }
    if (a.rfind("--", 0) == 0 && a.size() > 2) {
      std::string name = a.substr(2), value;
      bool has_inline = false;
      if (auto eq = name.find('='); eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
        has_inline = true;
      }
      const Opt* o = find(name);
      if (!o) {
        std::string best;
        int best_d = 4;
        for (const auto& c : opts_) {
          int d = editDistance(name, c.name);
          if (d < best_d) {
            best_d = d;
            best = c.name;
          }
        }
        return usageError("unknown option --" + name +
                          (best.empty() ? "" : " (did you mean --" + best + "?)"));
      }
      if (o->flag) {
        if (has_inline) return usageError("--" + name + " takes no value");
        *o->flag = true;
        continue;
      }
      if (!has_inline) {
        if (i + 1 >= args.size()) return usageError("--" + name + " needs a value " + o->meta);
        value = args[++i];
      }
      // An empty value would silently mean "not given" (e.g. --source '' running the default).
      if (value.empty()) return usageError("--" + name + " needs a non-empty value " + o->meta);
      if (o->value) *o->value = value;
      if (o->values) o->values->push_back(value);
      continue;
    }
    if (next_pos >= pos_.size()) return usageError("unexpected argument '" + a + "'");
    *pos_[next_pos++].value = a;
  }
  for (size_t p = next_pos; p < pos_.size(); ++p) {
    if (pos_[p].required) return usageError("missing argument <" + pos_[p].name + ">");
  }
  return std::nullopt;
}

}  // namespace emf::cli
