#include "page_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "mbsflow/error.hpp"

namespace mbsflow::cli {
namespace {

void send_all(int fd, const std::string& data) {
  std::size_t sent = 0;
  while (sent < data.size()) {
    const ssize_t n = ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return;  // the browser went away
    sent += static_cast<std::size_t>(n);
  }
}

void answer(int fd, const char* status, const char* type, const std::string& body) {
  send_all(fd, std::string("HTTP/1.1 ") + status + "\r\nContent-Type: " + type + "\r\nContent-Length: " +
                   std::to_string(body.size()) + "\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n" + body);
}

// The request line's target, from at most 16 KiB of headers read within 5 s.
std::string request_target(int fd) {
  std::string request;
  char buf[4096];
  while (request.find("\r\n\r\n") == std::string::npos && request.size() < 16384) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 5000) <= 0) break;
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    request.append(buf, static_cast<std::size_t>(n));
  }
  if (request.rfind("GET ", 0) != 0) return "";
  const std::size_t end = request.find(' ', 4);
  return end == std::string::npos ? "" : request.substr(4, end - 4);
}

}  // namespace

PageServer open_page_server(const std::string& host, int port) {
  PageServer s;
  s.socket = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (s.socket < 0) throw Error(std::string("mbsflow view: cannot make a socket: ") + std::strerror(errno));
  const int yes = 1;
  ::setsockopt(s.socket, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (::inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1) throw InputError("{host}: '" + host + "' is not an IPv4 address");
  if (::bind(s.socket, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(s.socket, 8) != 0)
    throw InputError("{port}: cannot listen on " + host + ":" + std::to_string(port) + ": " + std::strerror(errno));
  socklen_t len = sizeof a;
  ::getsockname(s.socket, reinterpret_cast<sockaddr*>(&a), &len);
  s.port = ntohs(a.sin_port);
  return s;
}

void serve_pages(PageServer& server, const std::function<std::string()>& page, const std::atomic<bool>* stop) {
  while (!stop->load()) {
    pollfd p{server.socket, POLLIN, 0};
    if (::poll(&p, 1, 200) <= 0) continue;
    const int fd = ::accept4(server.socket, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) continue;
    const std::string target = request_target(fd);
    if (target == "/" || target == "/index.html") {
      try {
        answer(fd, "200 OK", "text/html; charset=utf-8", page());
      } catch (const std::exception& e) {
        answer(fd, "500 Internal Server Error", "text/plain; charset=utf-8", e.what());
      }
    } else {
      answer(fd, "404 Not Found", "text/plain; charset=utf-8", "mbsflow view serves / only\n");
    }
    ::close(fd);
  }
  ::close(server.socket);
  server.socket = -1;
}

}  // namespace mbsflow::cli
