#!/bin/bash
# What CURVE costs: the same tight 2-worker run on loopback, insecure and keyed, three
# times alternating; prints the wall time each run reports and checks the results agree
# bit for bit. BODIES (2000) and TEND (0.5 s) set the run; ports 5701 and 5702 must be free.
M=${MBSFLOW:-$(cd "$(dirname "$0")/.." && pwd)/build/release/apps/mbsflow}
W=$(mktemp -d); trap 'rm -rf "$W"' EXIT; cd "$W"
$M generate chain --bodies ${BODIES:-2000} -o chain.json 2>/dev/null
kc=$($M keygen c 2>/dev/null); k0=$($M keygen w0 2>/dev/null); k1=$($M keygen w1 2>/dev/null)
echo "{\"coordinator\": {\"public_key\": \"$kc\"}, \"workers\": [{\"public_key\": \"$k0\"}, {\"public_key\": \"$k1\"}]}" > keys.json
one() {  # $1: keyed|insecure
  if [ $1 = keyed ]; then a0="--cluster keys.json --key w0.key"; a1="--cluster keys.json --key w1.key"; sk="\"secret_key\": \"c.key\","; pc=", \"public_key\": \"$kc\""; p0=", \"public_key\": \"$k0\""; p1=", \"public_key\": \"$k1\""; fl="";
  else a0="--insecure"; a1="--insecure"; sk=""; pc=""; p0=""; p1=""; fl="--insecure"; fi
  $M worker --listen tcp://127.0.0.1:5701 --threads 1 -q $a0 > /dev/null 2>&1 &
  $M worker --listen tcp://127.0.0.1:5702 --threads 1 -q $a1 > /dev/null 2>&1 &
  sleep 0.5
  echo "{$sk \"coordinator\": {\"bind\": \"tcp://127.0.0.1:*\"$pc}, \"workers\": [{\"address\": \"tcp://127.0.0.1:5701\", \"data_bind\": \"tcp://127.0.0.1:*\"$p0}, {\"address\": \"tcp://127.0.0.1:5702\", \"data_bind\": \"tcp://127.0.0.1:*\"$p1}]}" > $1.json
  wall=$($M run chain.json --t-end ${TEND:-0.5} --every 100 --cluster $1.json $fl -o $1.h5 2>&1 | sed -n "s/.* \([0-9.]*\) s wall.*/\1/p")
  wait
  printf "%-9s %s s\n" "$1" "$wall"
}
for i in 1 2 3; do one insecure; one keyed; done
h5diff -q keyed.h5 insecure.h5 /bodies /bodies && echo "keyed == insecure bit for bit"
