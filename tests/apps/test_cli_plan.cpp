// mbsflow plan end to end: the table's rows agree with the model it states (compute plus
// exchange per stage, four stages a step for RK4), one host of one thread is the baseline,
// and a slow network makes more hosts slower.
#include <catch2/catch.hpp>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "cli_support.hpp"

using namespace mbsflow::test;

namespace {

// The CSV rows by column name.
std::vector<std::map<std::string, double>> read_rows(const fs::path& csv) {
  std::istringstream in(read_text(csv));
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> names = csv_cells(line);
  std::vector<std::map<std::string, double>> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = csv_cells(line);
    std::map<std::string, double> row;
    for (std::size_t i = 0; i < names.size() && i < cells.size(); ++i) row[names[i]] = std::stod(cells[i]);
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

TEST_CASE("cli plan: rows follow the stated model and a slow network loses to one host", "[cli][plan]") {
  const fs::path d = scratch("plan");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 400 -o chain.json", dir).code == 0);
  const Result r = run("plan chain.json --hosts 4 --threads 2 --alpha-us 50 --bandwidth-mbs 100 --csv plan.csv", dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  CHECK_THAT(r.out, Catch::Contains("alpha 50.0 us, beta 100 MB/s"));
  const auto rows = read_rows(d / "plan.csv");
  REQUIRE(rows.size() == 4);  // 1x1, then 1, 2 and 4 hosts of 2 threads
  CHECK(rows[0].at("hosts") == 1);
  CHECK(rows[0].at("speedup") == 1.0);
  CHECK(rows[0].at("exchange_s_per_stage") == 0.0);
  CHECK(rows[3].at("hosts") == 4);
  CHECK(rows[3].at("threads") == 2);
  for (const auto& row : rows) {
    CHECK(row.at("s_per_step") == Approx(4 * (row.at("compute_s_per_stage") + row.at("exchange_s_per_stage"))).epsilon(1e-5));
    CHECK(row.at("speedup") == Approx(rows[0].at("s_per_step") / row.at("s_per_step")).epsilon(1e-5));
    // A chain cut into k submodels in a row: the hosts' messages (one body each) cross
    // the host boundaries both ways, and the slowest host hears at most two.
    const double hosts = row.at("hosts");
    CHECK(row.at("messages_per_stage") == 2 * (hosts - 1));
    CHECK(row.at("bytes_per_stage") == 2 * (hosts - 1) * (13 * 8 + 40));
    if (hosts > 1) CHECK(row.at("exchange_s_per_stage") == Approx((hosts > 2 ? 2 : 1) * (50e-6 + 144 / 100e6)).epsilon(1e-5));
  }
  // A second-long message: any second host makes the run slower than one.
  const Result slow = run("plan chain.json --hosts 2 --alpha-us 1e6 --bandwidth-mbs 100 --csv slow.csv", dir, true);
  REQUIRE(slow.code == 0);
  const auto srows = read_rows(d / "slow.csv");
  REQUIRE(srows.size() == 2);
  CHECK(srows[1].at("speedup") < 0.01);
  fs::remove_all(d.parent_path());
}

TEST_CASE("cli plan: implicit methods and missing models are refused with the reason", "[cli][plan]") {
  const fs::path d = scratch("plan-errors");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 10 -o chain.json", dir).code == 0);
  std::string text = read_text(d / "chain.json");
  const std::size_t at = text.find('{', text.find("\"simulation\""));
  REQUIRE(at != std::string::npos);
  text.insert(at + 1, "\"method\":\"tirk\",");
  std::ofstream(d / "tirk.json") << text;
  Result r = run("plan tirk.json", dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("integrate with rk4 or dopri5") && Catch::Contains("tirk"));
  r = run("plan missing.json", dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("missing.json"));
  fs::remove_all(d.parent_path());
}
