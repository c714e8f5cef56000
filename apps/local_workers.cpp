#include "local_workers.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "mbsflow/error.hpp"

namespace mbsflow::cli {
namespace {

// Starts `mbsflow worker ARGS` with its stdout on a pipe; returns the pid and the read end.
std::pair<pid_t, int> spawn_worker(const std::vector<std::string>& args) {
  int out[2];
  if (::pipe(out) != 0) throw RunError("cannot start a worker: no pipe");
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw RunError("cannot start a worker: fork failed");
  if (pid == 0) {
    // The worker dies with the coordinator, whatever kills it; Ctrl-C on the terminal
    // reaches only the coordinator (its own process group), which stops the workers.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    ::setpgid(0, 0);
    if (::getppid() != parent) ::_exit(1);
    ::dup2(out[1], STDOUT_FILENO);
    ::close(out[0]);
    ::close(out[1]);
    std::vector<char*> argv;
    static char self[] = "/proc/self/exe";
    argv.push_back(self);
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv("/proc/self/exe", argv.data());
    ::_exit(127);
  }
  ::close(out[1]);
  return {pid, out[0]};
}

// The endpoint a worker announces on its first line of output ("... listening on E").
std::string read_announcement(int fd, double timeout_s) {
  std::string line;
  const auto start = std::chrono::steady_clock::now();
  while (line.find('\n') == std::string::npos) {
    const double left = timeout_s - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    pollfd p{fd, POLLIN, 0};
    if (left <= 0) return "";
    const int ready = ::poll(&p, 1, static_cast<int>(left * 1000));
    if (ready < 0 && errno == EINTR) continue;  // a signal: the caller sees its stop flag later
    if (ready <= 0) return "";
    char buf[256];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return "";
    line.append(buf, static_cast<std::size_t>(n));
  }
  line.resize(line.find('\n'));
  const std::size_t at = line.rfind(' ');
  return at == std::string::npos ? "" : line.substr(at + 1);
}

}  // namespace

LocalWorkers::LocalWorkers(int n, const std::string& transport, int threads) {
  cluster_.transport = transport;
  cluster_.coordinator_name = "local";
  // An owner-only folder for the ipc endpoints and the run's keys: a key pair per process,
  // made for this run, so that no other local user can join it (mkdtemp makes it 0700).
  char dir[] = "/tmp/mbsflow-XXXXXX";
  if (!::mkdtemp(dir)) throw RunError("cannot make a directory for the local workers in /tmp");
  ipc_dir_ = dir;
  cluster_.results_bind = transport == "ipc" ? "ipc://" + ipc_dir_ + "/results" : "tcp://127.0.0.1:*";
  cluster_.keys = make_curve_keys();
  cluster_.coordinator_key = cluster_.keys->public_key;
  nlohmann::json keys = {{"coordinator", {{"public_key", cluster_.coordinator_key}}}, {"workers", nlohmann::json::array()}};
  std::vector<CurveKeyPair> pairs;
  for (int i = 0; i < n; ++i) {
    pairs.push_back(make_curve_keys());
    write_key_files(pairs.back(), ipc_dir_ + "/local" + std::to_string(i));
    keys["workers"].push_back({{"public_key", pairs.back().public_key}});
  }
  const std::string key_list = ipc_dir_ + "/keys.json";
  std::ofstream(key_list) << keys.dump() << '\n';
  for (int i = 0; i < n; ++i) {
    const std::string name = "local" + std::to_string(i);
    const std::string listen = transport == "ipc" ? "ipc://" + ipc_dir_ + "/" + name + ".control" : "tcp://127.0.0.1:*";
    std::vector<std::string> args = {"worker", "--listen", listen, "--threads", std::to_string(threads),
                                     "--idle-timeout", "60", "--quiet", "--cluster", key_list,
                                     "--key", ipc_dir_ + "/" + name + ".key"};
    auto [pid, fd] = spawn_worker(args);
    pids_.push_back(pid);
    const std::string endpoint = read_announcement(fd, 30.0);
    ::close(fd);
    if (endpoint.empty()) throw RunError("local worker " + std::to_string(i) + " did not start (see its message above)");
    ClusterWorker w;
    w.name = name;
    w.address = endpoint;
    w.data_bind = transport == "ipc" ? "ipc://" + ipc_dir_ + "/" + name + ".data" : "tcp://127.0.0.1:*";
    w.public_key = pairs[static_cast<std::size_t>(i)].public_key;
    cluster_.workers.push_back(w);
  }
}

namespace {
// Whether the process is stopped (state T or t in /proc/PID/stat).
bool stopped(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');  // the command name may hold spaces and parentheses
  return close != std::string::npos && close + 2 < text.size() && (text[close + 2] == 'T' || text[close + 2] == 't');
}
}  // namespace

LocalWorkers::~LocalWorkers() {
  // The run is over (finished, failed or never started): SIGTERM asks a worker that still
  // waits for its coordinator to give up; anything still there after 5 s is killed, so
  // that no process is left behind.
  // A stopped worker (SIGSTOP, a debugger) cannot take the SIGTERM: it is killed at once,
  // so that the run ends when its loss is noticed, not 5 s later.
  for (pid_t pid : pids_) ::kill(pid, SIGTERM);
  const auto start = std::chrono::steady_clock::now();
  for (pid_t pid : pids_) {
    while (true) {
      int status = 0;
      const pid_t got = ::waitpid(pid, &status, WNOHANG | WUNTRACED);
      if (got < 0 || (got == pid && !WIFSTOPPED(status))) break;  // ended (or not ours to wait for)
      const bool stuck = got == pid || stopped(pid);
      if (stuck || std::chrono::steady_clock::now() - start > std::chrono::seconds(5)) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, nullptr, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  {
    std::error_code ignored;
    std::filesystem::remove_all(ipc_dir_, ignored);
  }
}

}  // namespace mbsflow::cli
