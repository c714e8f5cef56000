// libFuzzer target: the wire decoders a peer's bytes reach first: control messages
// (parse_control and the typed field readers), a set-up's run and loose-coupling options
// (options_from_json, loose_from_json: refused with InputError, never converted out of
// range) and the binary frame headers.
#include <cstddef>
#include <cstdint>
#include <zmq.hpp>

#include "cluster_wire.hpp"
#include "mbsflow/error.hpp"
#include "options_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mbsflow;
  const zmq::message_t m(data, size);
  for (const auto run : {std::optional<std::uint64_t>(), std::optional<std::uint64_t>(0x0123456789abcdefull)})
    if (const auto j = wire::parse_control(m, run)) {
      (void)wire::text(*j, "type");
      (void)wire::text(*j, "reason");
      (void)wire::number(*j, "protocol", -1e9, 1e9);
      if (const auto t = j->find("timeouts"); t != j->end() && t->is_object()) (void)wire::number(*t, "lost_s", 1e-3, 600.0);
      for (const char* key : {"options", "loose"}) {
        const auto o = j->find(key);
        if (o == j->end()) continue;
        try {
          if (key == std::string("options"))
            (void)options_from_json(*o);
          else
            (void)loose_from_json(*o);
        } catch (const InputError&) {
        } catch (const nlohmann::json::exception&) {
        }
      }
    }
  (void)wire::read_header<wire::ExchangeHeader>(m, 0);
  (void)wire::read_header<wire::ResultHeader>(m, 0);
  return 0;
}
