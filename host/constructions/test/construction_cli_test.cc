// SPDX-License-Identifier: MIT
// The command-line tool (FDSURF_BINARY) on the construction examples.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace fdsurf::host {
namespace {

// ---- The command-line tool on the examples ----------------------------------

struct ToolRun {
  int exit_code = -1;
  std::string out;
};

ToolRun RunTool(const std::string& args) {
  ToolRun r;
  const std::string command = std::string(FDSURF_BINARY) + " " + args + " 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) r.out.append(buffer, n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(ConstructionCli, SamplesCurvesWithTheFixedEngine) {
  const ToolRun r = RunTool("sample " FDSURF_EXAMPLES_DIR "/hermite-chain.json --grid 4");
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out.substr(0, 14), "curve,i,x,y,z\n");
  // x(1/2) = 1 + 6/4 − 4/8 = 2, y(1/2) = 1 + 1/2 − 1/4 = 1.25.
  EXPECT_NE(r.out.find("\n0,2,2.000,1.250,0.000\n"), std::string::npos) << r.out;
  const ToolRun check = RunTool("check " FDSURF_EXAMPLES_DIR "/hermite-chain.json --grid 100");
  EXPECT_EQ(check.exit_code, 0);
  EXPECT_NE(check.out.find("join 1 at (3, 1, 0): parametrically smooth (C1)"), std::string::npos);
  EXPECT_NE(check.out.find("curves: max error"), std::string::npos);
}

TEST(ConstructionCli, JoinsOnTheTeapotAndRefusedInput) {
  const ToolRun r = RunTool("joins " FDSURF_EXAMPLES_DIR "/teapot.bpt");
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("52 shared edges in 32 patches: 46 C1, 6 G1, 0 C0, 0 degenerate"),
            std::string::npos)
      << r.out;
  const char* bad = "/tmp/fdsurf_construction_test_bad.json";
  FILE* f = std::fopen(bad, "w");
  ASSERT_NE(f, nullptr);
  std::fputs(R"({"construct": [{"type": "lagrange-curves", "curves": []}]})", f);
  std::fclose(f);
  const ToolRun refused = RunTool(std::string("sample ") + bad + " --grid 4");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_TRUE(refused.out.empty());
  std::remove(bad);
}

}  // namespace
}  // namespace fdsurf::host
