#include "mbsflow/io/cluster_file.hpp"

#include <filesystem>
#include <limits>
#include <set>

#include "json_node.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

constexpr std::size_t max_cluster_bytes = std::size_t{16} << 20;

std::string folder_of(const std::string& path) {
  const std::string parent = std::filesystem::path(path).parent_path().string();
  return parent.empty() ? "." : parent;
}

// An endpoint of the cluster's transport; "host:port" or "/path" get the transport's prefix.
std::string endpoint(const JsonNode& n, const std::string& transport) {
  std::string e = n.string();
  const std::size_t scheme = e.find("://");
  if (scheme == std::string::npos) return transport + "://" + e;
  if (e.substr(0, scheme) != transport)
    n.fail("is a " + e.substr(0, scheme) + " endpoint, but the cluster's transport is " + transport);
  if (e.size() == scheme + 3) n.fail("names no address");
  return e;
}

// True for endpoints that bind every interface (peers cannot connect to them as written).
bool every_interface(const std::string& e) {
  return e.rfind("tcp://*:", 0) == 0 || e.rfind("tcp://0.0.0.0:", 0) == 0;
}

bool any_port(const std::string& e) { return e.size() > 2 && e.compare(e.size() - 2, 2, ":*") == 0; }

// An address for peers: given, or the bind endpoint when that names one host and port.
std::string address_for(const JsonNode& owner, const char* key, const std::string& bind, const char* bind_key,
                        const std::string& transport) {
  if (auto a = owner.find(key)) {
    const std::string e = endpoint(*a, transport);
    if (every_interface(e)) a->fail("must name a host the peers can reach, not every interface");
    return e;
  }
  if (every_interface(bind) && !any_port(bind))
    owner[bind_key].fail(std::string("binds every interface; give \"") + key + "\", the address peers connect to");
  return "";  // what the bind gets
}

std::string public_key(const JsonNode& n) {
  const std::string k = n.string();
  if (!is_curve_key(k)) n.fail("must be a CURVE public key: 40 characters of Z85, as `mbsflow keygen` writes in NAME.pub");
  return k;
}

std::string secret_key_path(const JsonNode& root, const std::string& base_dir) {
  const auto v = root.find("secret_key");
  if (!v) return "";
  const std::filesystem::path p = v->string();
  return (p.is_absolute() ? p : std::filesystem::path(base_dir) / p).string();
}

ClusterConfig read(const JsonNode& root, const std::string& base_dir) {
  root.expect_object();
  root.allow_only({"transport", "timeouts", "coordinator", "workers", "secret_key"});
  ClusterConfig c;
  if (const std::string secret = secret_key_path(root, base_dir); !secret.empty()) {
    try {
      c.keys = read_secret_key_file(secret);
    } catch (const InputError& e) {
      root["secret_key"].fail(e.what());
    }
  }
  if (auto t = root.find("transport")) {
    c.transport = t->string();
    if (c.transport != "tcp" && c.transport != "ipc") t->fail("must be \"tcp\" or \"ipc\" (got \"" + c.transport + "\")");
  }
  if (auto t = root.find("timeouts")) {
    t->expect_object();
    t->allow_only({"connect_s", "heartbeat_s", "lost_s", "stall_s"});
    auto seconds = [](const JsonNode& v, const char* key, double max) {
      const double x = v.positive();
      if (x > max) v.fail(std::string(key) + " must be at most " + number_text(max) + " s (got " + number_text(x) + ")");
      return x;
    };
    if (auto v = t->find("connect_s")) c.timeouts.connect_s = seconds(*v, "connect_s", ClusterTimeouts::max_connect_s);
    if (auto v = t->find("heartbeat_s")) c.timeouts.heartbeat_s = seconds(*v, "heartbeat_s", ClusterTimeouts::max_heartbeat_s);
    if (auto v = t->find("lost_s")) c.timeouts.lost_s = seconds(*v, "lost_s", ClusterTimeouts::max_lost_s);
    if (auto v = t->find("stall_s")) c.timeouts.stall_s = seconds(*v, "stall_s", ClusterTimeouts::max_stall_s);
    if (c.timeouts.lost_s <= 2.0 * c.timeouts.heartbeat_s)
      t->fail("lost_s must be more than twice heartbeat_s, or a peer that is merely slow counts as lost");
  }
  const JsonNode co = root["coordinator"];
  co.expect_object();
  co.allow_only({"name", "bind", "address", "public_key"});
  if (auto v = co.find("name")) c.coordinator_name = v->string();
  if (auto v = co.find("public_key")) c.coordinator_key = public_key(*v);
  c.results_bind = endpoint(co["bind"], c.transport);
  c.results_address = address_for(co, "address", c.results_bind, "bind", c.transport);

  const JsonNode ws = root["workers"];
  const std::size_t n = ws.array_size();
  if (n == 0) ws.fail("must list at least one worker");
  std::set<std::string> names, addresses;
  for (std::size_t i = 0; i < n; ++i) {
    const JsonNode w = ws.item(i);
    w.expect_object();
    w.allow_only({"name", "listen", "address", "data_bind", "data_address", "weight", "submodels", "threads", "public_key"});
    ClusterWorker cw;
    cw.name = w.has("name") ? w["name"].string() : "worker" + std::to_string(i);
    if (!names.insert(cw.name).second) w["name"].fail("\"" + cw.name + "\" names two workers");
    // The coordinator connects to `address`; `listen` is what the worker was started with.
    const std::string listen = w.has("listen") ? endpoint(w["listen"], c.transport) : "";
    if (w.has("address")) {
      cw.address = address_for(w, "address", listen, "listen", c.transport);
    } else if (!listen.empty() && !every_interface(listen) && !any_port(listen)) {
      cw.address = listen;
    } else {
      (w.has("listen") ? w["listen"] : w).fail(
          "give \"address\", where the coordinator reaches the worker's --listen endpoint");
    }
    if (!addresses.insert(cw.address).second)
      w[w.has("address") ? "address" : "listen"].fail(cw.address + " is the address of two workers");
    cw.data_bind = endpoint(w["data_bind"], c.transport);
    cw.data_address = address_for(w, "data_address", cw.data_bind, "data_bind", c.transport);
    if (auto v = w.find("weight")) cw.weight = static_cast<int>(v->integer(1, 1'000'000));
    if (auto v = w.find("public_key")) cw.public_key = public_key(*v);
    if (auto v = w.find("threads")) cw.threads = static_cast<int>(v->integer(0, 65536));
    if (auto v = w.find("submodels")) {
      const std::size_t m = v->array_size();
      if (m == 0) v->fail("must list at least one submodel");
      for (std::size_t j = 0; j < m; ++j) cw.submodels.push_back(static_cast<int>(v->item(j).integer(0, std::numeric_limits<int>::max())));
    }
    if ((i > 0) && (cw.submodels.empty() != c.workers.front().submodels.empty()))
      w.fail("list \"submodels\" for every worker or for none");
    c.workers.push_back(std::move(cw));
  }
  return c;
}

}  // namespace

ClusterConfig read_cluster_text(const std::string& text, const std::string& name, const std::string& base_dir) {
  const nlohmann::json j = parse_json_document(text, name);
  JsonSource src{name, JsonLocations(text)};
  return read(JsonNode(j, "", src), base_dir);
}

ClusterConfig read_cluster_file(const std::string& path) {
  return read_cluster_text(read_input_file(path, "cluster file", max_cluster_bytes), path, folder_of(path));
}

ClusterKeyFile read_cluster_keys(const std::string& path) {
  const std::string text = read_input_file(path, "cluster file", max_cluster_bytes);
  const nlohmann::json j = parse_json_document(text, path);
  JsonSource src{path, JsonLocations(text)};
  const JsonNode root(j, "", src);
  root.expect_object();
  ClusterKeyFile out;
  out.secret_key_file = secret_key_path(root, folder_of(path));
  const JsonNode co = root["coordinator"];
  co.expect_object();
  out.keys.coordinator = public_key(co["public_key"]);
  const JsonNode ws = root["workers"];
  for (std::size_t i = 0; i < ws.array_size(); ++i) {
    ws.item(i).expect_object();
    out.keys.workers.push_back(public_key(ws.item(i)["public_key"]));
  }
  return out;
}

}  // namespace mbsflow
