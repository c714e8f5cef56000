#!/usr/bin/env bash
# A loosely coupled run across two network namespaces joined by a veth pair, one worker in
# each, with 20 ms added to every packet each way by tc netem where the kernel has it
# (else by mbsflow's own --exchange-delay, and the test says so).
#   1. exact lag: the results file is bit for bit the one-process run's (h5diff);
#   2. newest values with a lag of 2: the submodels ran ahead on older values, never
#      more than 2 macro steps, and the result stays close to the one-process run.
# Needs root and `ip netns` (iproute2); where the machine does not allow it, the test
# exits 77, which ctest reports as skipped, with the reason.
# Usage: netns_cluster.sh MBSFLOW_EXE WORK_DIR
set -uo pipefail
exe=$1
work=$2
skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAILED: $*"; exit 1; }

[ "$(id -u)" -eq 0 ] || skip "not root: network namespaces need it"
command -v ip >/dev/null || skip "no ip command (iproute2)"
command -v h5diff >/dev/null || skip "no h5diff (hdf5-tools)"
a=mbsf_a_$$
b=mbsf_b_$$
net=10.211.$(($$ % 250))
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  wait 2>/dev/null
  ip netns del "$a" 2>/dev/null
  ip netns del "$b" 2>/dev/null
}
trap cleanup EXIT
ip netns add "$a" 2>/dev/null || skip "ip netns add is not allowed here"
ip netns add "$b" || skip "ip netns add is not allowed here"
ip link add "va$$" type veth peer name "vb$$" || skip "cannot create a veth pair"
ip link set "va$$" netns "$a" && ip link set "vb$$" netns "$b" || fail "cannot move the veth ends"
ip -n "$a" addr add "$net.1/24" dev "va$$" && ip -n "$b" addr add "$net.2/24" dev "vb$$" || fail "cannot address the veth ends"
for ns in "$a" "$b"; do ip -n "$ns" link set lo up; done
ip -n "$a" link set "va$$" up && ip -n "$b" link set "vb$$" up || fail "cannot bring the veth ends up"

delay=""
if ip netns exec "$a" tc qdisc add dev "va$$" root netem delay 20ms 2>/dev/null &&
   ip netns exec "$b" tc qdisc add dev "vb$$" root netem delay 20ms 2>/dev/null; then
  echo "tc netem: 20 ms each way on the veth pair"
else
  delay="--exchange-delay 0.02"
  echo "tc netem is not available here (no sch_netem): the 20 ms come from --exchange-delay instead"
fi

rm -rf "$work" && mkdir -p "$work" && cd "$work" || fail "cannot make $work"
"$exe" generate chain --bodies 60 -o chain.json >/dev/null || fail "generate"
# A key pair per process (CURVE): the run across the two namespaces is authenticated.
kc=$("$exe" keygen coordinator 2>/dev/null) && ka=$("$exe" keygen a 2>/dev/null) && kb=$("$exe" keygen b 2>/dev/null) ||
  fail "keygen"
cat > cluster.json <<JSON
{"transport": "tcp", "timeouts": {"connect_s": 10, "heartbeat_s": 0.5, "lost_s": 5}, "secret_key": "coordinator.key",
 "coordinator": {"name": "a", "bind": "tcp://$net.1:5550", "public_key": "$kc"},
 "workers": [
   {"name": "a", "listen": "tcp://$net.1:5560", "data_bind": "tcp://$net.1:5561", "threads": 1, "public_key": "$ka"},
   {"name": "b", "listen": "tcp://$net.2:5560", "data_bind": "tcp://$net.2:5561", "threads": 1, "public_key": "$kb"}]}
JSON
common="--t-end 0.05 --step 1e-4 --every 100 --partitions 3 --coupling loose --extrapolation 2"

# One run on the two namespaces' workers (each serves one run and exits).
across() {
  pids=()
  ip netns exec "$a" "$exe" worker --listen "tcp://$net.1:5560" --cluster cluster.json --key a.key >"worker_a.log" 2>&1 & pids+=($!)
  ip netns exec "$b" "$exe" worker --listen "tcp://$net.2:5560" --cluster cluster.json --key b.key >"worker_b.log" 2>&1 & pids+=($!)
  ip netns exec "$a" "$exe" run chain.json $common --cluster cluster.json $delay "$@"
  local rc=$?
  wait "${pids[@]}" 2>/dev/null
  pids=()
  return $rc
}

"$exe" run chain.json $common --macro-step 2e-4 --threads 2 --max-lag 2 --exact-lag -q -o local_exact.h5 || fail "one-process exact-lag run"
start=$(date +%s%N)
across --macro-step 2e-4 --max-lag 2 --exact-lag -o netns_exact.h5 2>exact.err || { cat exact.err; fail "exact-lag run across the namespaces"; }
echo "exact lag 2 across the namespaces: $(( ($(date +%s%N) - start) / 1000000 )) ms wall"
tail -2 exact.err
h5diff netns_exact.h5 local_exact.h5 /bodies/position || fail "exact lag: positions differ from the one-process run"
h5diff netns_exact.h5 local_exact.h5 /coupling/position_error || fail "exact lag: coupling errors differ"

"$exe" run chain.json $common --macro-step 1e-4 --threads 2 -q -o local_sync.h5 || fail "one-process run"
across --max-lag 2 --macro-step 1e-4 -o netns_newest.h5 2>newest.err || { cat newest.err; fail "newest-value run across the namespaces"; }
tail -2 newest.err
grep -q "at most 2 steps old" newest.err || fail "newest values: the submodels never ran ahead (or more than 2 steps)"
/usr/bin/python3 - <<'PY' || fail "newest values: too far from the one-process run"
import h5py, numpy as np
a = h5py.File("netns_newest.h5")["bodies/position"][()]
b = h5py.File("local_sync.h5")["bodies/position"][()]
lag = h5py.File("netns_newest.h5")["coupling/lag"][()]
gap = np.abs(a - b).max()
print(f"newest values, lag up to {lag.max()}: largest position difference from the synchronous run {gap:.3g} m")
assert lag.max() == 2 and gap < 1e-4
PY
echo "PASSED"
