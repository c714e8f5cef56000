// mbsflow keygen NAME: a CURVE key pair for one host of a cluster (docs/reliability.md).
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/runtime/curve_keys.hpp"

namespace mbsflow::cli {

Action add_keygen(CLI::App& app) {
  auto stem = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand(
      "keygen", "Write a CURVE key pair for one host: NAME.key (secret, owner-only) and NAME.pub (name it in the cluster file)");
  sub->add_option("name", *stem, "Path without extension, e.g. keys/host1")->required();
  return [stem] {
    // The folder is made if missing (~/.mbsflow on a fresh account), owner-only like the key.
    const std::filesystem::path folder = std::filesystem::path(*stem).parent_path();
    std::error_code ec;
    if (!folder.empty() && !std::filesystem::exists(folder, ec)) {
      std::filesystem::create_directories(folder, ec);
      if (ec) throw InputError("cannot make the folder " + folder.string() + " for the keys: " + ec.message());
      std::filesystem::permissions(folder, std::filesystem::perms::owner_all, ec);
      std::fprintf(stderr, "mbsflow: made the folder %s (owner-only)\n", folder.c_str());
    }
    const CurveKeyPair k = make_curve_keys();
    write_key_files(k, *stem);
    std::printf("%s\n", k.public_key.c_str());
    std::fprintf(stderr, "mbsflow: wrote %s.key (secret, mode 600) and %s.pub; public key above\n", stem->c_str(), stem->c_str());
    return 0;
  };
}

}  // namespace mbsflow::cli
