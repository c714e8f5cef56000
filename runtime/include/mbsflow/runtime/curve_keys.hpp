#pragma once
// CURVE key pairs for authenticated, encrypted runs across hosts (ZeroMQ CURVE; see
// docs/reliability.md). Keys are Z85 text of 40 characters.
#include <string>
#include <vector>

namespace mbsflow {

struct CurveKeyPair {
  std::string public_key, secret_key;
};

// True for 40 characters of the Z85 alphabet.
bool is_curve_key(const std::string& z85);
// A new pair; InputError if this libzmq was built without CURVE.
CurveKeyPair make_curve_keys();
// Writes STEM.key (both keys, owner-only permissions, created so: never readable by others
// even for a moment) and STEM.pub (the public key). InputError if STEM.key exists.
void write_key_files(const CurveKeyPair& keys, const std::string& stem);
// Reads a .key file; InputError if it is missing, malformed, or readable by group or others.
CurveKeyPair read_secret_key_file(const std::string& path);

// The public keys a run admits, from the cluster file: the coordinator's (on a worker's
// control socket) and the workers' (on the coordinator's results inbox and the workers'
// data inboxes).
struct ClusterKeys {
  std::string coordinator;
  std::vector<std::string> workers;
};

}  // namespace mbsflow
