#pragma once
// mbsflow processes that a test starts, watches, kills and always reaps: for the
// multi-process tests (workers and coordinators on 127.0.0.1 only).
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cli_support.hpp"
#include "mbsflow/io/results_file.hpp"

namespace mbsflow::test {

class Child {
 public:
  // Starts `mbsflow ARGS` in dir with stdout and stderr going to files there, and the
  // variables of env ("NAME=VALUE") set.
  Child(const std::vector<std::string>& args, const fs::path& dir, const std::string& name,
        const std::vector<std::string>& env = {})
      : out_(dir / (name + ".out")), err_(dir / (name + ".err")) {
    pid_ = ::fork();
    REQUIRE(pid_ >= 0);
    if (pid_ == 0) {
      if (::chdir(dir.c_str()) != 0 || !std::freopen(out_.c_str(), "w", stdout) || !std::freopen(err_.c_str(), "w", stderr))
        ::_exit(126);
      for (const std::string& e : env) {
        const std::size_t eq = e.find('=');
        ::setenv(e.substr(0, eq).c_str(), e.substr(eq + 1).c_str(), 1);
      }
      std::vector<char*> argv{const_cast<char*>(MBSFLOW_EXE)};
      for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(MBSFLOW_EXE, argv.data());
      ::_exit(127);
    }
  }
  ~Child() {
    if (!code_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  pid_t pid() const { return pid_; }
  void kill(int sig) const { ::kill(pid_, sig); }

  // The exit code once it has ended (-signal if a signal ended it); nullopt if it is still
  // running after `seconds`.
  std::optional<int> wait(double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (!code_) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
        break;
      }
      if (std::chrono::steady_clock::now() > end) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return code_;
  }

  std::string out() const { return read_text(out_); }
  std::string err() const { return read_text(err_); }

  // A worker's endpoint from its first line ("mbsflow worker: listening on E").
  std::string endpoint(double seconds = 20.0) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      const std::string o = out();
      const std::size_t nl = o.find('\n');
      if (nl != std::string::npos) return o.substr(o.rfind(' ', nl) + 1, nl - o.rfind(' ', nl) - 1);
      if (wait(0.0)) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return "";
  }

 private:
  pid_t pid_ = -1;
  fs::path out_, err_;
  std::optional<int> code_;
};

// Whether two results files hold the same times and body states, bit for bit (and more
// than two snapshots, so that an empty run does not pass).
inline bool same_results(const fs::path& a, const fs::path& b) {
  const mbsflow::ResultsFile x(a.string()), y(b.string());
  bool same = x.time() == y.time() && x.time().size() > 2;
  for (const char* set : {"/bodies/position", "/bodies/orientation", "/bodies/velocity", "/bodies/angular_velocity"})
    same = same && x.read(set) == y.read(set);
  return same;
}

}  // namespace mbsflow::test
