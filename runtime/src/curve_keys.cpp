#include "mbsflow/runtime/curve_keys.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <zmq.h>

#include "mbsflow/error.hpp"

namespace mbsflow {

bool is_curve_key(const std::string& z85) {
  static const std::string alphabet =
      "0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ.-:+=^!/*?&<>()[]{}@%$#";
  return z85.size() == 40 && z85.find_first_not_of(alphabet) == std::string::npos;
}

CurveKeyPair make_curve_keys() {
  if (!zmq_has("curve")) throw InputError("this libzmq has no CURVE security; install Debian's libzmq5");
  char pub[41], sec[41];
  if (zmq_curve_keypair(pub, sec) != 0) throw InputError(std::string("cannot make a CURVE key pair: ") + zmq_strerror(zmq_errno()));
  return {pub, sec};
}

void write_key_files(const CurveKeyPair& keys, const std::string& stem) {
  const std::string key = stem + ".key", pub = stem + ".pub";
  const int fd = ::open(key.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) throw InputError("cannot create " + key + ": " + std::strerror(errno) + (errno == EEXIST ? " (a key is never overwritten)" : ""));
  const std::string text = "# mbsflow CURVE key pair: keep this file secret\npublic-key = " + keys.public_key +
                           "\nsecret-key = " + keys.secret_key + "\n";
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ::close(fd);
  if (!ok) throw InputError("cannot write " + key);
  std::ofstream out(pub);
  out << "# mbsflow CURVE public key: name it in the cluster file\npublic-key = " << keys.public_key << "\n";
  if (!out) throw InputError("cannot write " + pub);
}

CurveKeyPair read_secret_key_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw InputError(path + ": cannot open the secret key file: " + std::strerror(errno));
  if (st.st_mode & (S_IRWXG | S_IRWXO))
    throw InputError(path + ": the secret key file is readable by others (chmod 600 it, or make a new one with `mbsflow keygen`)");
  if (st.st_size > 4096) throw InputError(path + ": not a key file (too large)");
  std::ifstream in(path);
  CurveKeyPair k;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string name, eq, value;
    if (!(words >> name >> eq >> value) || eq != "=") continue;
    if (name == "public-key") k.public_key = value;
    if (name == "secret-key") k.secret_key = value;
  }
  if (!is_curve_key(k.public_key) || !is_curve_key(k.secret_key))
    throw InputError(path + ": not a key file of `mbsflow keygen` (public-key and secret-key lines of 40 Z85 characters)");
  char derived[41];
  if (zmq_curve_public(derived, k.secret_key.c_str()) != 0 || k.public_key != derived)
    throw InputError(path + ": its public key does not belong to its secret key");
  return k;
}

}  // namespace mbsflow
