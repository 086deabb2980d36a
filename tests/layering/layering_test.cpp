// The layers of docs/architecture.md, enforced: the module graph the build declares
// (cmake/EmfModules.cmake -> module_graph.txt) against the #include lines of the sources.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "include_graph.h"
#include "test_support.h"

namespace emf::layering {
namespace {
namespace fs = std::filesystem;

std::vector<Module> buildGraph() {
  return readModuleGraph(std::string(EMF_TEST_BINARY_DIR) + "/module_graph.txt");
}

std::string joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  return text;
}

TEST(Layering, EveryFolderOfSrcIsAModule) {
  std::set<std::string> folders;
  for (const Module& m : buildGraph()) folders.insert(m.folder);
  for (const auto& entry : fs::directory_iterator(fs::path(EMF_SOURCE_DIR) / "src")) {
    if (!entry.is_directory()) continue;
    const std::string folder = "src/" + entry.path().filename().string();
    EXPECT_TRUE(folders.count(folder)) << folder << " is not a module: add emf_add_module() or "
                                       << "emf_module_graph_entry() to its CMakeLists.txt";
  }
  EXPECT_TRUE(folders.count("firmware_host"));
}

TEST(Layering, EveryIncludeOfAnotherModuleIsDeclared) {
  const std::vector<Module> modules = buildGraph();
  const std::vector<Include> includes = scanIncludes(EMF_SOURCE_DIR, modules);
  // The tree has hundreds of includes between modules: a scan that finds few read nothing.
  constexpr size_t kMinIncludesBetweenModules = 150;
  EXPECT_GE(includes.size(), kMinIncludesBetweenModules);
  const std::vector<std::string> problems = undeclaredIncludes(modules, includes);
  EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST(Layering, NoCycleBetweenModules) {
  const std::vector<Module> modules = buildGraph();
  std::map<std::string, std::set<std::string>> declared, included;
  for (const Module& m : modules) declared[m.name].insert(m.depends.begin(), m.depends.end());
  for (const Include& inc : scanIncludes(EMF_SOURCE_DIR, modules)) {
    included[inc.from_module].insert(inc.to_module);
  }
  EXPECT_EQ(findCycle(declared), "");
  EXPECT_EQ(findCycle(included), "");
}

// The directions the architecture rests on, so that a dependency is not simply declared away.
TEST(Layering, TheBottomModulesStayAtTheBottom) {
  const std::vector<Module> modules = buildGraph();
  const auto allowed = [&](const std::string& m) { return allowedModules(modules, m); };
  EXPECT_EQ(allowed("common"), (std::set<std::string>{"api"}));
  EXPECT_EQ(allowed("core"), (std::set<std::string>{"api", "common"}));
  EXPECT_EQ(allowed("cl"), (std::set<std::string>{"api", "common"}));
  for (const char* lower : {"map", "track", "em"}) {
    for (const char* upper : {"io", "synth", "eval", "sources", "firmware_host", "pipeline"}) {
      EXPECT_FALSE(allowed(lower).count(upper)) << lower << " may not depend on " << upper;
    }
  }
  for (const char* upper : {"synth", "eval", "sources", "firmware_host", "pipeline"}) {
    EXPECT_FALSE(allowed("io").count(upper)) << "io may not depend on " << upper;
  }
  EXPECT_FALSE(allowed("firmware_host").count("io")) << "sensors and datasets share core only";
  EXPECT_FALSE(allowed("pipeline").count("sources")) << "the pipeline takes frames, not URIs";
}

TEST(Layering, TheCheckFindsAnUndeclaredIncludeAndACycle) {
  const fs::path root = fs::path(::testing::TempDir()) / "emf-layering-fixture";
  fs::remove_all(root);
  fs::create_directories(root / "src/low");
  fs::create_directories(root / "src/high");
  std::ofstream(root / "src/low/a.h") << "#pragma once\n#include <vector>\n#include \"high/b.h\"\n";
  std::ofstream(root / "src/high/b.h") << "#pragma once\n#include \"low/a.h\"\n";
  const std::vector<Module> modules = {{"low", "src/low", {}}, {"high", "src/high", {"low"}}};

  const std::vector<Include> includes = scanIncludes(root.string(), modules);
  ASSERT_EQ(includes.size(), 2u);
  const std::vector<std::string> problems = undeclaredIncludes(modules, includes);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("src/low/a.h:3: module 'low' includes a header of 'high'"),
            std::string::npos)
      << problems[0];

  std::map<std::string, std::set<std::string>> edges;
  for (const Include& inc : includes) edges[inc.from_module].insert(inc.to_module);
  EXPECT_EQ(findCycle(edges), "high -> low -> high");
  edges["low"].clear();
  EXPECT_EQ(findCycle(edges), "");
  fs::remove_all(root);
}

}  // namespace
}  // namespace emf::layering
