#pragma once
// What the command-line tests share: running the built `cisamr` with a time limit, and a
// fresh folder per test for inputs and outputs.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace cisamr::test {

struct CommandResult {
  int exit_code;
  std::string output;  // stdout and stderr
  double seconds;
};

// `cisamr ARGS` (a shell command line); a run that hangs is killed after 60 s and fails the
// test instead of the suite.
inline CommandResult run_cisamr(const std::string& args) {
  const std::string cmd = "timeout 60 " + std::string(CISAMR_BINARY_DIR) + "/bin/cisamr " + args + " 2>&1";
  const auto start = std::chrono::steady_clock::now();
  FILE* pipe = popen(cmd.c_str(), "r");
  CommandResult r{-1, {}, 0};
  if (!pipe) return r;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

// A test with its own empty folder, removed afterwards.
class CliFolder : public ::testing::Test {
 protected:
  std::filesystem::path dir;
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir = std::filesystem::temp_directory_path() /
          ("cisamr-" + std::string(info->test_suite_name()) + "-" + std::to_string(::getpid()) + "-" + info->name());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
  }
  void TearDown() override { std::filesystem::remove_all(dir); }
  std::string write(const std::string& name, const std::string& text) const {
    const std::filesystem::path p = dir / name;
    std::ofstream(p) << text;
    return p.string();
  }
};

}  // namespace cisamr::test
