#include "mbsflow/io/slurm.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <charconv>
#include <string_view>

#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

[[noreturn]] void bad_list(const std::string& list, const std::string& why) {
  throw InputError("Slurm host list '" + list + "': " + why);
}

// Splits at commas outside brackets.
std::vector<std::string> top_level_items(const std::string& list) {
  std::vector<std::string> items;
  std::string cur;
  int depth = 0;
  for (char c : list) {
    if (c == '[') ++depth;
    if (c == ']' && --depth < 0) bad_list(list, "']' without '['");
    if (c == ',' && depth == 0) {
      items.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (depth != 0) bad_list(list, "'[' without ']'");
  items.push_back(cur);
  return items;
}

// The pieces between commas ("a,,b" has an empty one; "" is one empty piece).
std::vector<std::string_view> comma_pieces(std::string_view s) {
  std::vector<std::string_view> out;
  for (std::size_t start = 0;;) {
    const std::size_t comma = std::min(s.find(',', start), s.size());
    out.push_back(s.substr(start, comma - start));
    if (comma == s.size()) return out;
    start = comma + 1;
  }
}

long parse_index(std::string_view s, const std::string& list) {
  long v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || v < 0) bad_list(list, "'" + std::string(s) + "' is not a number");
  return v;
}

// "01-03,7" -> 01 02 03 7: the width of a range is its lower bound's, as Slurm writes it.
std::vector<std::string> expand_ranges(const std::string& body, const std::string& list, std::size_t max_hosts) {
  std::vector<std::string> out;
  for (const std::string_view part : comma_pieces(body)) {
    const std::size_t dash = part.find('-');
    const std::string_view lo_text = part.substr(0, dash);
    const long lo = parse_index(lo_text, list);
    const long hi = dash == std::string_view::npos ? lo : parse_index(part.substr(dash + 1), list);
    if (hi < lo) bad_list(list, "range '" + std::string(part) + "' runs backwards");
    if (static_cast<std::size_t>(hi - lo) >= max_hosts) bad_list(list, "more than " + std::to_string(max_hosts) + " hosts");
    for (long i = lo; i <= hi; ++i) {
      std::string n = std::to_string(i);
      if (n.size() < lo_text.size()) n.insert(0, lo_text.size() - n.size(), '0');
      out.push_back(std::move(n));
    }
  }
  return out;
}

int parse_env_int(const EnvLookup& get, const char* name, int min) {
  const char* v = get(name);
  if (!v) throw InputError(std::string("--slurm: ") + name + " is not set (start the run with srun)");
  int x = 0;
  const std::string_view s(v);
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || x < min)
    throw InputError(std::string("--slurm: ") + name + "='" + v + "' is not a whole number >= " + std::to_string(min));
  return x;
}

const char* first_set(const EnvLookup& get, const char* a, const char* b) {
  const char* v = get(a);
  return v ? v : get(b);
}

bool numeric_address(const std::string& host) {
  unsigned char buf[16];
  return ::inet_pton(AF_INET, host.c_str(), buf) == 1 || ::inet_pton(AF_INET6, host.c_str(), buf) == 1;
}

std::string tcp(const std::string& host, int port) {
  return "tcp://" + (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

std::string bind_host(const std::string& host) { return numeric_address(host) ? host : "*"; }

}  // namespace

std::vector<std::string> expand_hostlist(const std::string& list, std::size_t max_hosts) {
  std::vector<std::string> hosts;
  for (const std::string& item : top_level_items(list)) {
    if (item.empty()) continue;  // "a,,b" or a trailing comma
    // Each bracket group multiplies the names so far: a[1-2]b[3-4] -> a1b3 a1b4 a2b3 a2b4.
    std::vector<std::string> names{""};
    std::size_t pos = 0;
    while (pos < item.size()) {
      const std::size_t open = item.find('[', pos);
      const std::string fixed = item.substr(pos, open == std::string::npos ? std::string::npos : open - pos);
      for (std::string& n : names) n += fixed;
      if (open == std::string::npos) break;
      const std::size_t close = item.find(']', open);
      if (close == std::string::npos) bad_list(list, "'[' without ']'");
      const std::vector<std::string> indices = expand_ranges(item.substr(open + 1, close - open - 1), list, max_hosts);
      if (names.size() * indices.size() > max_hosts) bad_list(list, "more than " + std::to_string(max_hosts) + " hosts");
      std::vector<std::string> next;
      next.reserve(names.size() * indices.size());
      for (const std::string& n : names)
        for (const std::string& i : indices) next.push_back(n + i);
      names = std::move(next);
      pos = close + 1;
    }
    hosts.insert(hosts.end(), names.begin(), names.end());
    if (hosts.size() > max_hosts) bad_list(list, "more than " + std::to_string(max_hosts) + " hosts");
  }
  if (hosts.empty()) bad_list(list, "names no host");
  return hosts;
}

std::vector<int> expand_tasks_per_node(const std::string& spec) {
  std::vector<int> out;
  const auto bad = [&] { throw InputError("Slurm tasks per node '" + spec + "': expected counts like 2(x3),1"); };
  for (const std::string_view part : comma_pieces(spec)) {
    int count = 0, repeat = 1;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), count);
    if (ec != std::errc() || count < 1) bad();
    const std::string_view rest(end, static_cast<std::size_t>(part.data() + part.size() - end));
    if (!rest.empty()) {
      if (rest.size() < 4 || rest.substr(0, 2) != "(x" || rest.back() != ')') bad();
      const auto [e2, ec2] = std::from_chars(rest.data() + 2, rest.data() + rest.size() - 1, repeat);
      if (ec2 != std::errc() || e2 != rest.data() + rest.size() - 1 || repeat < 1 || repeat > (1 << 20)) bad();
    }
    out.insert(out.end(), static_cast<std::size_t>(repeat), count);
  }
  return out;
}

SlurmStep slurm_step_from_env(const EnvLookup& get) {
  SlurmStep s;
  const int ntasks = parse_env_int(get, "SLURM_NTASKS", 1);
  s.rank = parse_env_int(get, "SLURM_PROCID", 0);
  if (s.rank >= ntasks)
    throw InputError("--slurm: SLURM_PROCID=" + std::to_string(s.rank) + " is not below SLURM_NTASKS=" + std::to_string(ntasks));
  if (const char* j = get("SLURM_JOB_ID")) s.job_id = std::strtol(j, nullptr, 10);
  if (get("SLURM_CPUS_PER_TASK")) s.cpus_per_task = parse_env_int(get, "SLURM_CPUS_PER_TASK", 1);
  const char* nodelist = first_set(get, "SLURM_STEP_NODELIST", "SLURM_JOB_NODELIST");
  if (!nodelist) throw InputError("--slurm: neither SLURM_STEP_NODELIST nor SLURM_JOB_NODELIST is set (start the run with srun)");
  const std::vector<std::string> nodes = expand_hostlist(nodelist);
  const char* per_node_text = first_set(get, "SLURM_STEP_TASKS_PER_NODE", "SLURM_TASKS_PER_NODE");
  std::vector<int> per_node;
  if (per_node_text) {
    per_node = expand_tasks_per_node(per_node_text);
  } else {  // as even as Slurm would make it: the first nodes take one more
    for (std::size_t n = 0; n < nodes.size(); ++n)
      per_node.push_back(ntasks / static_cast<int>(nodes.size()) + (static_cast<int>(n) < ntasks % static_cast<int>(nodes.size())));
  }
  if (per_node.size() != nodes.size())
    throw InputError("--slurm: " + std::to_string(nodes.size()) + " nodes in the node list but tasks given for " +
                     std::to_string(per_node.size()));
  long total = 0;
  for (int c : per_node) total += c;
  if (total != ntasks)
    throw InputError("--slurm: the tasks per node add up to " + std::to_string(total) + ", SLURM_NTASKS is " + std::to_string(ntasks));
  const char* given_distribution = get("SLURM_DISTRIBUTION");
  std::string distribution = given_distribution ? given_distribution : "block";
  distribution = distribution.substr(0, distribution.find_first_of(":,"));
  std::vector<int> node_of;  // by rank
  if (distribution == "block") {
    for (std::size_t n = 0; n < nodes.size(); ++n) node_of.insert(node_of.end(), static_cast<std::size_t>(per_node[n]), static_cast<int>(n));
  } else if (distribution == "cyclic") {
    std::vector<int> left = per_node;
    while (static_cast<int>(node_of.size()) < ntasks)
      for (std::size_t n = 0; n < nodes.size(); ++n)
        if (left[n] > 0) --left[n], node_of.push_back(static_cast<int>(n));
  } else {
    throw InputError("--slurm: SLURM_DISTRIBUTION '" + distribution + "' is not supported: start with srun --distribution=block or cyclic");
  }
  std::vector<int> placed(nodes.size(), 0);
  for (int node : node_of) {
    s.task_hosts.push_back(nodes[static_cast<std::size_t>(node)]);
    s.task_local.push_back(placed[static_cast<std::size_t>(node)]++);
  }
  return s;
}

int slurm_base_port(const SlurmStep& s) { return 20000 + 40 * static_cast<int>(s.job_id % 1000); }

std::string slurm_worker_listen(const SlurmStep& s, int base_port, int rank) {
  const auto r = static_cast<std::size_t>(rank);
  return tcp(bind_host(s.task_hosts[r]), base_port + 2 * s.task_local[r]);
}

ClusterConfig slurm_cluster(const SlurmStep& s, int base_port, const CurveKeyPair& keys) {
  if (base_port < 1 || base_port + 2 * s.tasks() > 65535)
    throw InputError("--slurm-port " + std::to_string(base_port) + ": the run needs ports up to base + 2 x tasks per node, below 65536");
  ClusterConfig c;
  c.transport = "tcp";
  c.coordinator_name = "slurm task 0 (" + s.task_hosts[0] + ")";
  c.results_bind = tcp(bind_host(s.task_hosts[0]), base_port);
  c.results_address = tcp(s.task_hosts[0], base_port);
  c.keys = keys;
  c.coordinator_key = keys.public_key;
  for (int r = 1; r < s.tasks(); ++r) {
    const auto i = static_cast<std::size_t>(r);
    ClusterWorker w;
    w.name = "task " + std::to_string(r) + " (" + s.task_hosts[i] + ")";
    const int port = base_port + 2 * s.task_local[i];
    w.address = tcp(s.task_hosts[i], port);
    w.data_bind = tcp(bind_host(s.task_hosts[i]), port + 1);
    w.data_address = tcp(s.task_hosts[i], port + 1);
    w.threads = s.cpus_per_task;
    w.public_key = keys.public_key;
    c.workers.push_back(w);
  }
  return c;
}

}  // namespace mbsflow
