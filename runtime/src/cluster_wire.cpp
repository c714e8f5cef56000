#include "cluster_wire.hpp"

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdio>

#include "json_depth.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow::wire {

std::int64_t max_data_bytes(const StateLayout& state) {
  // The whole state twice for headroom, and 64 MiB for the coupling records of a run.
  return static_cast<std::int64_t>(state.size()) * 8 * 2 + (std::int64_t{64} << 20);
}

std::string hex(const std::vector<std::uint8_t>& bytes) {
  static const char digits[] = "0123456789abcdef";
  std::string out(2 * bytes.size(), '0');
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    out[2 * i] = digits[bytes[i] >> 4];
    out[2 * i + 1] = digits[bytes[i] & 15];
  }
  return out;
}

std::optional<std::vector<std::uint8_t>> unhex(const std::string& text) {
  if (text.size() % 2 != 0) return std::nullopt;
  auto value = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return -1;
  };
  std::vector<std::uint8_t> out(text.size() / 2);
  for (std::size_t i = 0; i < out.size(); ++i) {
    const int hi = value(text[2 * i]), lo = value(text[2 * i + 1]);
    if (hi < 0 || lo < 0) return std::nullopt;
    out[i] = static_cast<std::uint8_t>(hi << 4 | lo);
  }
  return out;
}

zmq::socket_t make_socket(zmq::context_t& ctx, zmq::socket_type type, std::int64_t max_bytes) {
  zmq::socket_t s(ctx, type);
  s.set(zmq::sockopt::linger, 0);
  s.set(zmq::sockopt::maxmsgsize, max_bytes);
  return s;
}

void curve_server(zmq::socket_t& s, const Security* security, const char* domain) {
  if (!security) return;
  s.set(zmq::sockopt::curve_server, true);
  s.set(zmq::sockopt::curve_secretkey, security->mine.secret_key);
  s.set(zmq::sockopt::zap_domain, domain);
}

void curve_client(zmq::socket_t& s, const Security* security, const std::string& server_key) {
  if (!security) return;
  s.set(zmq::sockopt::curve_serverkey, server_key);
  s.set(zmq::sockopt::curve_publickey, security->mine.public_key);
  s.set(zmq::sockopt::curve_secretkey, security->mine.secret_key);
}

bool loopback(const std::string& e) {
  if (e.rfind("ipc://", 0) == 0 || e.rfind("inproc://", 0) == 0) return true;
  if (e.rfind("tcp://", 0) != 0) return false;
  const std::size_t port = e.rfind(':');  // the one of "tcp:" when no port follows
  const std::string host = e.substr(6, port > 6 ? port - 6 : std::string::npos);
  return host.rfind("127.", 0) == 0 || host == "localhost" || host == "[::1]";
}

void bind(zmq::socket_t& s, const std::string& endpoint, const std::string& what) {
  try {
    s.bind(endpoint);
  } catch (const zmq::error_t& e) {
    throw InputError("cannot bind " + what + " at " + endpoint + ": " + e.what());
  }
}

void connect(zmq::socket_t& s, const std::string& endpoint, const std::string& what) {
  try {
    s.connect(endpoint);
  } catch (const zmq::error_t& e) {
    throw InputError("cannot connect to " + what + " at " + endpoint + ": " + e.what());
  }
}

std::string reachable_address(zmq::socket_t& bound, const std::string& configured, const std::string& what) {
  if (!configured.empty()) return configured;
  const std::string got = bound.get(zmq::sockopt::last_endpoint);
  if (got.find("0.0.0.0") != std::string::npos || got.find("[::]") != std::string::npos)
    throw InputError(what + " binds every interface (" + got + "); give the address its peers use to reach it");
  return got;
}

int poll(zmq::pollitem_t* items, std::size_t n, double seconds) {
  try {
    // Clamped: a wait computed from a huge or NaN timeout must not overflow the cast.
    const double ms = std::clamp(seconds * 1000.0, 0.0, 3.6e6);
    return zmq::poll(items, n, std::chrono::milliseconds(static_cast<long>(std::isnan(ms) ? 0.0 : ms)));
  } catch (const zmq::error_t& e) {
    if (e.num() == EINTR) return 0;
    throw;
  }
}

namespace {
template <class F>
auto retrying(F f) {
  while (true) {
    try {
      return f();
    } catch (const zmq::error_t& e) {
      if (e.num() != EINTR) throw;
    }
  }
}
}  // namespace

zmq::recv_result_t recv(zmq::socket_t& s, zmq::message_t& m, zmq::recv_flags flags) {
  return retrying([&] { return s.recv(m, flags); });
}
zmq::send_result_t send(zmq::socket_t& s, zmq::const_buffer b, zmq::send_flags flags) {
  return retrying([&] { return s.send(b, flags); });
}
zmq::send_result_t send(zmq::socket_t& s, zmq::message_t& m, zmq::send_flags flags) {
  return retrying([&] { return s.send(m, flags); });
}

bool send_json(zmq::socket_t& s, const nlohmann::json& j, zmq::send_flags flags) {
  const std::string text = j.dump();
  return send(s, zmq::buffer(text), flags).has_value();
}

std::string integer_list_text(const std::vector<int>& v) {
  std::string out;
  out.reserve(v.size() * 3);
  char buf[16];
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i) out += ',';
    const auto r = std::to_chars(buf, buf + sizeof buf, v[i]);
    out.append(buf, r.ptr);
  }
  return out;
}

std::optional<std::vector<int>> integer_list(std::string_view text, int lo, int hi) {
  std::vector<int> out;
  if (text.empty()) return out;
  const char* at = text.data();
  const char* end = at + text.size();
  while (true) {
    int v = 0;
    const auto r = std::from_chars(at, end, v);
    if (r.ec != std::errc() || v < lo || v > hi) return std::nullopt;
    out.push_back(v);
    if (r.ptr == end) return out;
    if (*r.ptr != ',') return std::nullopt;
    at = r.ptr + 1;
  }
}

std::size_t parsed_bytes_bound(std::string_view text) {
  // Each value, member or element of nlohmann::json costs at most about 48 bytes beyond
  // its text (the value, a map node and its key, a vector's slack); each starts after one
  // of these characters outside a string (or is the first).
  std::size_t values = 1;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == ',' || c == '[' || c == '{' || c == ':') {
      ++values;
    }
  }
  return text.size() + 48 * values;
}

std::optional<nlohmann::json> parse_control(const zmq::message_t& m, std::optional<std::uint64_t> run) {
  const char* text = static_cast<const char*>(m.data());
  // The control messages nest 4 levels: deeper text is not parsed at all.
  if (json_too_deep({text, m.size()}, 16) != std::string_view::npos) return std::nullopt;
  // Nor text whose parse would cost more than a small multiple of its size (a list of
  // small integers takes about 25 bytes a byte: long ones travel as text).
  if (parsed_bytes_bound({text, m.size()}) > max_parse_factor * m.size() + (std::size_t{64} << 20)) return std::nullopt;
  nlohmann::json j = nlohmann::json::parse(text, text + m.size(), nullptr, false);
  if (!j.is_object() || !j.contains("type") || !j["type"].is_string()) return std::nullopt;
  if (run && wire::text(j, "run") != id_text(*run)) return std::nullopt;
  return j;
}

std::string text(const nlohmann::json& j, const char* key, const std::string& otherwise) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : otherwise;
}

std::optional<double> number(const nlohmann::json& j, const char* key, double lo, double hi) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return std::nullopt;
  const double v = it->get<double>();
  if (!(v >= lo && v <= hi)) return std::nullopt;
  return v;
}

void skip_rest(zmq::socket_t& s, const zmq::message_t& last) {
  bool more = last.more();
  while (more) {
    zmq::message_t part;
    if (!recv(s, part)) return;
    more = part.more();
  }
}

}  // namespace mbsflow::wire
