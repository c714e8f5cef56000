#pragma once
// A minimal HTTP server for mbsflow view --serve: answers GET / with a page made afresh
// for each request, everything else with 404; one request at a time, on one address.
#include <atomic>
#include <functional>
#include <string>

namespace mbsflow::cli {

struct PageServer {
  int socket = -1;
  int port = 0;  // the port bound (the one asked for, or the system's choice for 0)
};

// Binds host:port (port 0: any free one). Throws Error when it cannot.
PageServer open_page_server(const std::string& host, int port);
// Serves until *stop turns true; `page` makes the body of GET /, and its exceptions
// become 500 answers with their message.
void serve_pages(PageServer& server, const std::function<std::string()>& page, const std::atomic<bool>* stop);

}  // namespace mbsflow::cli
