// End-to-end tests of results files: SIGTERM mid-run, XDMF sidecar, info, export, plot.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <regex>
#include <sstream>
#include <thread>

#include "cli_support.hpp"
#include "mbsflow/error.hpp"
#include "process_support.hpp"
#include "mbsflow/io/results_file.hpp"

using namespace mbsflow::test;

TEST_CASE("a run stopped by SIGTERM exits with 1 and keeps every completed snapshot", "[apps]") {
  const fs::path d = scratch("sigterm");
  REQUIRE(run("generate chain --bodies 200 -o chain.json", d.string()).code == 0);
  const fs::path err = d / "stderr.txt", h5 = d / "run.h5";
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    if (::chdir(d.c_str()) != 0) ::_exit(99);
    if (!std::freopen(err.c_str(), "w", stderr)) ::_exit(99);
    ::execl(MBSFLOW_EXE, "mbsflow", "run", "chain.json", "--t-end", "1000", "--every", "5", "-o", "run.h5", nullptr);
    ::_exit(98);
  }
  // Wait until the first chunk row (16 snapshots of 200 bodies, 333 kB) is on disk, however
  // slow this build is, then ask the run to stop.
  const auto start = std::chrono::steady_clock::now();
  while ((!fs::exists(h5) || fs::file_size(h5) < 400000) && std::chrono::steady_clock::now() - start < std::chrono::seconds(300))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  REQUIRE(::kill(pid, SIGTERM) == 0);
  int status = 0;
  pid_t done = 0;
  for (int i = 0; i < 200 && done == 0; ++i) {  // must end within 10 s
    done = ::waitpid(pid, &status, WNOHANG);
    if (done == 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (done == 0) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
    FAIL("the run did not stop within 10 s of SIGTERM");
  }
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 1);
  const std::string message = read_text(err);
  INFO(message);
  std::smatch m;
  // Snapshots still queued for a slow disk are dropped to stop in time, and counted.
  REQUIRE(std::regex_search(
      message, m,
      std::regex(R"(interrupted at t = \S+ s(?:; \d+ snapshots not yet written were dropped to stop in time)?; results keep (\d+) snapshots up to t = (\S+) s \(SIGTERM\))")));
  const std::size_t kept = std::stoul(m[1]);
  const mbsflow::ResultsFile r(h5.string());
  const std::vector<double> t = r.time();
  CHECK(t.size() == kept);
  CHECK(kept >= 16);
  CHECK(t.back() == Approx(std::stod(m[2])).epsilon(1e-5));
  CHECK(r.shape("/bodies/position") == std::vector<std::uint64_t>{kept, 200, 3});
  for (std::size_t i = 1; i < t.size(); ++i) CHECK(t[i] > t[i - 1]);
  if (std::system("command -v h5dump >/dev/null 2>&1") == 0)
    CHECK(std::system(("h5dump -H '" + h5.string() + "' >/dev/null 2>&1").c_str()) == 0);
  CHECK(fs::exists(d / "run.xdmf"));
  fs::remove_all(d.parent_path());
}

TEST_CASE("results: info, CSV export, a consistent XDMF sidecar and a plot", "[apps]") {
  const fs::path d = scratch("results");
  const std::string dir = d.string();
  REQUIRE(run("generate grid --rows 3 --cols 4 -o grid.json", dir).code == 0);
  REQUIRE(run("run grid.json --t-end 0.2 --every 20 --fields all -o grid.h5", dir).code == 0);
  const Result info = run("info grid.h5", dir, true);
  CHECK(info.code == 0);
  CHECK(info.out.find("model         grid-3x4: 12 bodies, 20 joints with forces") != std::string::npos);
  CHECK(info.out.find("/bodies/position         ") != std::string::npos);
  CHECK(run("info grid.json", dir).code == 2);
  const Result exported = run("export grid.h5 --csv csv --bodies p0_0,p2_3", dir);
  CHECK(exported.code == 0);
  CHECK(fs::exists(d / "csv" / "p2_3.csv"));
  CHECK(run("export grid.h5 --csv csv --bodies nobody", dir).code == 2);
  const std::string python = MBSFLOW_PYTHON;
  const std::string check_xdmf = python + " '" + MBSFLOW_TESTS + "/io/check_xdmf.py' '" + dir;
  // 12 bodies: the values in the sidecar (the joints' forces too: 20 joints, 60 values a view).
  CHECK(std::system((check_xdmf + "/grid.xdmf' --position-views text --column-views text").c_str()) == 0);
  // 30 bodies: 90 values a view, past the limit for text; the rows read where they lie in
  // the series' chunks (binary items); the per-body energies, 30 values a view, text.
  REQUIRE(run("generate grid --rows 5 --cols 6 -o mid.json", dir).code == 0);
  REQUIRE(run("run mid.json --t-end 0.1 --output-interval 0.01 -o mid.h5", dir).code == 0);
  CHECK(std::system((check_xdmf + "/mid.xdmf' --position-views binary --column-views text").c_str()) == 0);
  // 300 bodies: a row spans two chunks (256 bodies each), so no binary items; 11 snapshots
  // are 79 kB of positions, copies of the rows; 501 snapshots 3.6 MB, past the limit for
  // copies: virtual datasets; the per-body energies (a column of their series, 300 values a
  // view) are gathered into tables read in place (binary items) either way.
  REQUIRE(run("generate grid --rows 15 --cols 20 -o big.json", dir).code == 0);
  REQUIRE(run("run big.json --t-end 0.01 --output-interval 0.001 -o short.h5", dir).code == 0);
  CHECK(std::system((check_xdmf + "/short.xdmf' --position-views compact --column-views binary").c_str()) == 0);
  REQUIRE(run("run big.json --t-end 0.5 --output-interval 0.001 -o big.h5", dir).code == 0);
  CHECK(std::system((check_xdmf + "/big.xdmf' --position-views virtual --column-views binary").c_str()) == 0);
  const int plot = std::system((python + " '" + MBSFLOW_SOURCE + "/scripts/plot.py' '" + dir + "/grid.h5' -o '" + dir + "/grid.png' >/dev/null").c_str());
  CHECK(plot == 0);
  CHECK(fs::exists(d / "grid.png"));
  fs::remove_all(d.parent_path());
}

TEST_CASE("a diverged run leaves a readable results file with what it computed", "[apps]") {
  const fs::path d = scratch("diverged");
  REQUIRE(run("generate chain --bodies 10 --step 0.01 -o chain.json", d.string()).code == 0);
  const Result r = run("run chain.json --t-end 1 -o out.h5", d.string());
  REQUIRE(r.code == 1);
  std::smatch m;
  REQUIRE(std::regex_search(r.err, m, std::regex(R"(results keep (\d+) snapshots)")));
  const mbsflow::ResultsFile results((d / "out.h5").string());
  CHECK(results.time().size() == std::stoul(m[1]));
  CHECK(results.time().size() >= 1);
  fs::remove_all(d.parent_path());
}

TEST_CASE("the progress line shows on a terminal only", "[apps]") {
  const fs::path d = scratch("progress");
  REQUIRE(run("generate chain --bodies 2000 -o chain.json", d.string()).code == 0);
  // The line is first drawn 250 ms into a run: this one takes about 0.8 s on a fast core
  // (0.6 s of model time took 0.2 s there, and showed no line).
  const std::string args = "run chain.json --t-end 2";
  const Result piped = run(args, d.string());
  CHECK(piped.code == 0);
  CHECK(piped.err.find("ETA") == std::string::npos);
  CHECK(piped.err.find("mbsflow: done: ") != std::string::npos);
  if (std::system("command -v script >/dev/null 2>&1") == 0) {
    // script(1) runs the command on a pseudo-terminal and copies what it shows to stdout.
    const std::string cmd = "cd '" + d.string() + "' && script -qec \"'" + std::string(MBSFLOW_EXE) + "' " + args +
                            "\" /dev/null > tty.txt 2>&1";
    REQUIRE(std::system(cmd.c_str()) == 0);
    const std::string shown = read_text(d / "tty.txt");
    CHECK(shown.find("ETA") != std::string::npos);
    CHECK(shown.find("steps/s") != std::string::npos);
    const Result quiet = run(args + " --quiet", d.string());
    CHECK(quiet.err.find("ETA") == std::string::npos);
  }
  fs::remove_all(d.parent_path());
}

TEST_CASE("joint reactions and motor efforts: info lists them, export writes a CSV per joint, plot draws them",
          "[apps][rigid]") {
  const fs::path d = scratch("joint-results");
  const std::string dir = d.string();
  const std::string model = std::string(MBSFLOW_SOURCE) + "/examples/models/slider_crank.json";
  REQUIRE(run("run '" + model + "' --t-end 0.5 --fields all -q -o crank.h5", dir).code == 0);
  const Result info = run("info crank.h5", dir, true);
  CHECK(info.code == 0);
  CHECK_THAT(info.out, Catch::Contains("/joints/force") && Catch::Contains("/joints/motor_effort"));
  REQUIRE(run("export crank.h5 --csv csv", dir).code == 0);
  for (const char* joint : {"shaft", "crank_pin", "wrist_pin", "guide"}) CHECK(fs::exists(d / "csv" / ("joint_" + std::string(joint) + ".csv")));
  // The motor holds the crank's speed against gravity: its effort is not zero.
  const mbsflow::ResultsFile f((d / "crank.h5").string());
  const std::vector<double> effort = f.read("/joints/motor_effort");
  CHECK(std::any_of(effort.begin(), effort.end(), [](double e) { return std::abs(e) > 1.0; }));
  const std::string python = MBSFLOW_PYTHON;
  CHECK(std::system((python + " '" + MBSFLOW_SOURCE + "/scripts/plot.py' '" + dir + "/crank.h5' -o '" + dir + "/crank.png' >/dev/null").c_str()) == 0);
  CHECK(fs::exists(d / "crank.png"));
  fs::remove_all(d.parent_path());
}

TEST_CASE("the results of mbsflow ode: info describes them and export and plot read them", "[apps]") {
  const fs::path d = scratch("ode_results");
  const std::string dir = d.string();
  REQUIRE(run("ode --problem hnw --tol 1e-5 -o hnw.h5", dir).code == 0);
  const Result info = run("info hnw.h5", dir, true);
  CHECK(info.code == 0);
  INFO(info.out);
  CHECK(info.out.find("problem       hnw: 4 equations (mbsflow ode)") != std::string::npos);
  CHECK(info.out.find("max error") != std::string::npos);
  const mbsflow::ResultsFile r((d / "hnw.h5").string());
  REQUIRE(r.ode());
  REQUIRE(run("export hnw.h5 --csv csv", dir).code == 0);
  const std::string solution = read_text(d / "csv" / "solution.csv");
  CHECK(solution.rfind("t,y1,y2,y3,y4,error\n", 0) == 0);
  CHECK(static_cast<std::size_t>(std::count(solution.begin(), solution.end(), '\n')) == r.time().size() + 1);
  const std::string steps = read_text(d / "csv" / "steps.csv");
  CHECK(static_cast<std::size_t>(std::count(steps.begin(), steps.end(), '\n')) == r.shape("/steps/t").at(0) + 1);
  CHECK(run("export hnw.h5 --csv csv --bodies b", dir).code == 2);
  CHECK(run("plot hnw.h5 -o hnw.png", dir).code == 0);
  CHECK(fs::exists(d / "hnw.png"));
  const Result view = run("view hnw.h5", dir);
  CHECK(view.code == 2);
  CHECK(view.err.find("hold no bodies to show") != std::string::npos);
  fs::remove_all(d.parent_path());
}

TEST_CASE("a run's results are read while it goes by info and h5py and plot --follow and view --serve and view writes its motion", "[apps]") {
  const fs::path d = scratch("live");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 300 -o chain.json", dir).code == 0);
  Child writer({"run", "chain.json", "--t-end", "1000", "--every", "5", "-o", "live.h5"}, d, "writer");
  // Until two flushes are on disk, however slow this build is.
  const auto start = std::chrono::steady_clock::now();
  long rows = 0;
  while (rows < 32 && std::chrono::steady_clock::now() - start < std::chrono::seconds(300) && !writer.wait(0.0)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    if (fs::exists(d / "live.h5")) {
      try {
        rows = static_cast<long>(mbsflow::ResultsFile((d / "live.h5").string()).time().size());
      } catch (const mbsflow::InputError&) {  // a file not yet renamed into place
      }
    }
  }
  REQUIRE(rows >= 32);
  REQUIRE_FALSE(writer.wait(0.0));
  {
    // Opened twice, the second time while the first is held: HDF5 hands the second the
    // file the first opened, and it must know that file is live (refresh what it reads).
    const mbsflow::ResultsFile first((d / "live.h5").string());
    const mbsflow::ResultsFile second((d / "live.h5").string());
    CHECK(first.live());
    CHECK(second.live());
    const std::size_t seen = second.time().size();
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    CHECK(second.time().size() > seen);
  }
  const Result info = run("info live.h5", dir, true);
  CHECK(info.code == 0);
  CHECK(info.out.find("(run ended early)") != std::string::npos);  // not at t_end yet: still going
  const std::string python = MBSFLOW_PYTHON;
  const std::string read = python + " -c \"import h5py,sys,time; f = h5py.File(sys.argv[1], 'r', swmr=True); t = f['time'];"
                           " n = t.shape[0]; time.sleep(1.5); t.refresh(); sys.exit(0 if t.shape[0] > n else 1)\" '" +
                           dir + "/live.h5'";
  CHECK(std::system(read.c_str()) == 0);  // h5py sees it grow
  // view --serve: each load is made afresh from the file; a live run's page reloads itself.
  Child server({"view", "live.h5", "--serve", "--port", "0", "--interval", "1"}, d, "server");
  std::string address;
  for (int i = 0; i < 600 && address.empty() && !server.wait(0.0); ++i) {
    std::smatch m;
    const std::string first = server.out();
    if (std::regex_search(first, m, std::regex(R"(at (http://127\.0\.0\.1:\d+/))"))) address = m[1];
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  REQUIRE_FALSE(address.empty());
  // Last time shown and refresh period of the served page, twice 1.5 s apart (not the frame count:
  // past --max-frames the snapshots are spread evenly, so the count can fall as the run grows).
  const std::string fetch = python + " -c \"import json,re,sys,time,urllib.request\n"
                            "def data():\n"
                            "    page = urllib.request.urlopen(sys.argv[1]).read().decode()\n"
                            "    return json.loads(re.search(r'const DATA = (\\{.*?\\});\\n', page, re.S).group(1))\n"
                            "a = data(); time.sleep(1.5); b = data()\n"
                            "print(repr(a['t'][-1]), a['refresh'], repr(b['t'][-1]), b['refresh'])\" " +
                            address + " > '" + dir + "/served.txt'";
  REQUIRE(std::system(fetch.c_str()) == 0);
  std::istringstream served(read_text(d / "served.txt"));
  double last_before = 0, last_after = 0, refresh_before = 0, refresh_after = 0;
  served >> last_before >> refresh_before >> last_after >> refresh_after;
  CHECK(last_after > last_before);  // new snapshots in the page
  CHECK(refresh_before == 1.0);         // and it reloads itself
  Child follower({"plot", "live.h5", "--follow", "--interval", "0.3", "-o", "live.png"}, d, "follower");
  // Until the follower has drawn the live run once: on a loaded CI machine its first
  // frame (Python and matplotlib starting) can take longer than any fixed pause.
  const auto follow_start = std::chrono::steady_clock::now();
  while (follower.out().find("(run going)") == std::string::npos && !follower.wait(0.0) &&
         std::chrono::steady_clock::now() - follow_start < std::chrono::seconds(120))
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  writer.kill(SIGTERM);
  CHECK(writer.wait(60.0) == 1);
  CHECK(follower.wait(60.0) == 0);
  const std::string lines = follower.out();
  INFO(lines);
  CHECK(lines.find("(run going)") != std::string::npos);
  CHECK(lines.find("(run ended)") != std::string::npos);
  CHECK(fs::exists(d / "live.png"));
  const std::string ended = python + " -c \"import json,re,sys,urllib.request\n"
                            "page = urllib.request.urlopen(sys.argv[1]).read().decode()\n"
                            "sys.exit(0 if json.loads(re.search(r'const DATA = (\\{.*?\\});\\n', page, re.S).group(1))['refresh'] == 0 else 1)\" " +
                            address;
  CHECK(std::system(ended.c_str()) == 0);  // the finished run's page stays put
  server.kill(SIGINT);
  CHECK(server.wait(10.0) == 0);
  const Result view = run("view live.h5 --max-frames 50", dir);
  CHECK(view.code == 0);
  std::smatch shown;  // at most 50 frames, evenly spread
  REQUIRE(std::regex_search(view.err, shown, std::regex(R"((\d+) frames)")));
  CHECK(std::stoi(shown[1]) <= 50);
  CHECK(std::stoi(shown[1]) >= 25);
  const std::string page = read_text(d / "live.html");
  CHECK(page.find("THREE.InstancedMesh") != std::string::npos);  // three.js inlined: no network
  CHECK(page.find("<script src") == std::string::npos);
  fs::remove_all(d.parent_path());
}
