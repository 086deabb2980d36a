// The module graph of the build (cmake/EmfModules.cmake writes it to module_graph.txt) and the
// include graph of the sources, with the two checks the layering test makes: every include of
// another module is declared in DEPENDS (directly or through a lower module), and no cycle.
#pragma once

#include <map>
#include <set>
#include <string>
#include <vector>

namespace emf::layering {

struct Module {
  std::string name;
  std::string folder;                // relative to the source tree, e.g. "src/map"
  std::vector<std::string> depends;  // declared DEPENDS
};

/// Reads module_graph.txt: "<module> <folder> <depends...>" per line. Throws on a malformed line.
std::vector<Module> readModuleGraph(const std::string& path);

/// One `#include "<prefix>/..."` of another module's header.
struct Include {
  std::string from_module;
  std::string to_module;
  std::string file;  // relative to the source tree
  int line = 0;
};

/// Every include, in the modules' folders, of a header of another module. A header belongs to
/// the module whose folder's last component is the first component of the include path.
std::vector<Include> scanIncludes(const std::string& source_root,
                                  const std::vector<Module>& modules);

/// The modules `module` may include: its DEPENDS and theirs, transitively.
std::set<std::string> allowedModules(const std::vector<Module>& modules, const std::string& module);

/// Includes of a module outside allowedModules(), one message each ("file:line: ...").
std::vector<std::string> undeclaredIncludes(const std::vector<Module>& modules,
                                            const std::vector<Include>& includes);

/// A cycle in the graph `edges` (module -> modules it uses) as "a -> b -> a", or "" if none.
std::string findCycle(const std::map<std::string, std::set<std::string>>& edges);

}  // namespace emf::layering
