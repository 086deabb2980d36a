#include "include_graph.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace emf::layering {
namespace fs = std::filesystem;

std::vector<Module> readModuleGraph(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the module graph " + path + " (configure first)");
  std::vector<Module> modules;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream words(line);
    Module m;
    if (!(words >> m.name)) continue;
    if (!(words >> m.folder)) {
      throw std::runtime_error(path + ":" + std::to_string(number) + ": module without a folder");
    }
    for (std::string d; words >> d;) m.depends.push_back(d);
    modules.push_back(m);
  }
  return modules;
}

std::vector<Include> scanIncludes(const std::string& source_root,
                                  const std::vector<Module>& modules) {
  std::map<std::string, std::string> by_prefix;  // include prefix -> module
  for (const Module& m : modules) by_prefix[fs::path(m.folder).filename().string()] = m.name;
  const std::regex include_re(R"(^\s*#\s*include\s*"([^"/]+)/[^"]*")");
  std::vector<Include> found;
  for (const Module& m : modules) {
    const fs::path folder = fs::path(source_root) / m.folder;
    if (!fs::is_directory(folder)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(folder)) {
      const std::string ext = entry.path().extension().string();
      if (!entry.is_regular_file() || (ext != ".h" && ext != ".cpp" && ext != ".c")) continue;
      std::ifstream in(entry.path());
      std::string line;
      int number = 0;
      while (std::getline(in, line)) {
        ++number;
        std::smatch match;
        if (!std::regex_search(line, match, include_re)) continue;
        const auto target = by_prefix.find(match[1].str());
        if (target == by_prefix.end() || target->second == m.name) continue;
        found.push_back(
            {m.name, target->second, fs::relative(entry.path(), source_root).string(), number});
      }
    }
  }
  return found;
}

std::set<std::string> allowedModules(const std::vector<Module>& modules,
                                     const std::string& module) {
  std::map<std::string, const Module*> by_name;
  for (const Module& m : modules) by_name[m.name] = &m;
  std::set<std::string> allowed;
  std::function<void(const std::string&)> visit = [&](const std::string& name) {
    const auto it = by_name.find(name);
    if (it == by_name.end()) return;
    for (const std::string& d : it->second->depends) {
      if (allowed.insert(d).second) visit(d);
    }
  };
  visit(module);
  return allowed;
}

std::vector<std::string> undeclaredIncludes(const std::vector<Module>& modules,
                                            const std::vector<Include>& includes) {
  std::map<std::string, std::set<std::string>> allowed;
  for (const Module& m : modules) allowed[m.name] = allowedModules(modules, m.name);
  std::vector<std::string> problems;
  for (const Include& inc : includes) {
    if (allowed[inc.from_module].count(inc.to_module)) continue;
    problems.push_back(inc.file + ":" + std::to_string(inc.line) + ": module '" + inc.from_module +
                       "' includes a header of '" + inc.to_module +
                       "', which is not in its DEPENDS (its CMakeLists.txt): move the code to "
                       "the lower module, or declare the dependency if the direction is right");
  }
  return problems;
}

std::string findCycle(const std::map<std::string, std::set<std::string>>& edges) {
  enum class Mark { kNew, kOnPath, kDone };
  std::map<std::string, Mark> mark;
  std::vector<std::string> path;
  std::string cycle;
  std::function<bool(const std::string&)> visit = [&](const std::string& node) {
    mark[node] = Mark::kOnPath;
    path.push_back(node);
    const auto out = edges.find(node);
    if (out != edges.end()) {
      for (const std::string& next : out->second) {
        if (mark[next] == Mark::kOnPath) {
          auto first = std::find(path.begin(), path.end(), next);
          for (auto it = first; it != path.end(); ++it) cycle += *it + " -> ";
          cycle += next;
          return true;
        }
        if (mark[next] == Mark::kNew && visit(next)) return true;
      }
    }
    path.pop_back();
    mark[node] = Mark::kDone;
    return false;
  };
  for (const auto& [node, _] : edges) {
    if (mark[node] == Mark::kNew && visit(node)) return cycle;
  }
  return "";
}

}  // namespace emf::layering
