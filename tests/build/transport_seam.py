"""The transport seam (docs/architecture.md): a worker's run loops reach ZeroMQ only through
runtime/src/worker_transport.hpp, the coordinator only through coordinator_transport.hpp.
Follows the project's own includes ("...") of each file and fails if <zmq.hpp> or a ZeroMQ
transport header is reached."""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1])
loops = ["runtime/src/worker_part.hpp", "runtime/src/worker_part.cpp", "runtime/src/worker_tight.cpp",
         "runtime/src/worker_loose.cpp", "runtime/src/worker_transport.hpp", "runtime/src/wire_format.hpp",
         "runtime/src/coordinator.cpp", "runtime/src/coordinator_transport.hpp"]
transport = {"cluster_wire.hpp", "remote_exchange.hpp", "worker_io.hpp", "zap_guard.hpp"}
search = [root / "base/internal"] + sorted(root.glob("*/include")) + sorted(root.glob("*/src"))
include = re.compile(r'^\s*#\s*include\s*([<"])([^">]+)[">]', re.M)


def resolve(name, here):
    for d in [here] + search:
        if (d / name).is_file():
            return d / name
    return None


def reaches(path, trail, seen):
    for kind, name in include.findall(path.read_text()):
        if kind == "<":
            if name.startswith("zmq"):
                return trail + [f"<{name}>"]
            continue
        if pathlib.Path(name).name in transport:
            return trail + [name]
        found = resolve(name, path.parent)
        if found is None or found in seen:
            continue
        seen.add(found)
        hit = reaches(found, trail + [str(found.relative_to(root))], seen)
        if hit:
            return hit
    return None


failures = 0
for f in loops:
    hit = reaches(root / f, [f], set())
    if hit:
        print("transport type reached:", " -> ".join(hit))
        failures += 1
    else:
        print("ok:", f)
sys.exit(1 if failures else 0)
