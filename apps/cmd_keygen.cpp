// mbsflow keygen NAME: a CURVE key pair for one host of a cluster (docs/reliability.md).
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "mbsflow/runtime/curve_keys.hpp"

namespace mbsflow::cli {

Action add_keygen(CLI::App& app) {
  auto stem = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand(
      "keygen", "Write a CURVE key pair for one host: NAME.key (secret, owner-only) and NAME.pub (name it in the cluster file)");
  sub->add_option("name", *stem, "Path without extension, e.g. keys/host1")->required();
  return [stem] {
    const CurveKeyPair k = make_curve_keys();
    write_key_files(k, *stem);
    std::printf("%s\n", k.public_key.c_str());
    std::fprintf(stderr, "mbsflow: wrote %s.key (secret, mode 600) and %s.pub; public key above\n", stem->c_str(), stem->c_str());
    return 0;
  };
}

}  // namespace mbsflow::cli
