#!/usr/bin/env python3
"""Floating-point operations per call of a function, counted from what the CPU executes.

Runs a command under valgrind's callgrind with instruction-level counts collected only
inside FUNCTION (and what it calls, libm included), disassembles every object those
instructions come from with objdump, and weighs each executed instruction by the double
operations it does: scalar add/sub/mul/div/sqrt 1, packed (SSE2, 2 lanes) 2, AVX 4,
fused multiply-add twice that; moves, logic (sign flips), compares, conversions, min/max
count 0. Divides by the number of calls of FUNCTION.

  scripts/count_flops.py 'mbsflow::MultibodySystem::rhs*' -- \\
      build/release/apps/mbsflow bench rhs --bodies 2000 --seconds 0.01 --csv /tmp/x.csv

prints: calls, flops per call, and the executed instructions per call.
"""
import collections
import re
import subprocess
import sys
import tempfile

ARITH = re.compile(r"^v?(add|sub|mul|div|sqrt)(s|p)d$")
FMA = re.compile(r"^vf(n?)m(add|sub|addsub|subadd)(132|213|231)(s|p)d$")


def flops_of(mnemonic, operands):
    wide = 4 if "ymm" in operands else 8 if "zmm" in operands else 2
    m = ARITH.match(mnemonic)
    if m:
        return 1 if m.group(2) == "s" else wide
    m = FMA.match(mnemonic)
    if m:
        return 2 if m.group(4) == "s" else 2 * wide
    return 0


def disassemble(path):
    """address -> (mnemonic, operands) of an object file."""
    out = subprocess.run(["objdump", "-d", "--no-show-raw-insn", path], capture_output=True, text=True).stdout
    table = {}
    for line in out.splitlines():
        m = re.match(r"^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$", line)
        if m:
            table[int(m.group(1), 16)] = (m.group(2), m.group(3))
    return table


def parse(path, function_pattern):
    """(object, address) -> executed count (self, inside the collected range); calls of the function."""
    names = {"ob": {}, "fn": {}, "cfn": {}}
    counts = collections.Counter()
    calls = 0
    ob = fn = None
    cfn = None
    skip_next = False
    last = 0
    target = re.compile(function_pattern.replace("*", ".*"))
    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            m = re.match(r"^(ob|fn|cfn|cob|fl|fi|fe|cfi|cfl)=\((\d+)\)(?: (.*))?$", line)
            if m:
                kind, ident, name = m.group(1), m.group(2), m.group(3)
                table = names.get({"cfn": "fn", "cob": "ob"}.get(kind, kind))
                if table is not None:
                    if name is not None:
                        table[ident] = name
                    value = table.get(ident, "")
                    if kind == "ob":
                        ob = value
                    elif kind == "fn":
                        fn = value
                    elif kind == "cfn":
                        cfn = value
                continue
            if line.startswith("calls="):
                if cfn and target.fullmatch(cfn.split("(")[0]) and not (fn and target.fullmatch(fn.split("(")[0])):
                    calls += int(line.split("=")[1].split()[0])
                skip_next = True  # the next line is the call's inclusive cost
                continue
            m = re.match(r"^([+-]\d+|0x[0-9a-fA-F]+|\*)\s+(\d+)", line)
            if not m:
                continue
            pos = m.group(1)
            addr = last if pos == "*" else last + int(pos) if pos[0] in "+-" else int(pos, 16)
            last = addr
            if skip_next:
                skip_next = False
                continue
            counts[(ob, addr)] += int(m.group(2))
    return counts, calls


def main():
    if "--" not in sys.argv or sys.argv.index("--") != 2:
        sys.exit(__doc__)
    function, command = sys.argv[1], sys.argv[3:]
    with tempfile.NamedTemporaryFile(suffix=".callgrind") as out:
        subprocess.run(["valgrind", "--tool=callgrind", "--dump-instr=yes", "--dump-line=no",
                        "--toggle-collect=" + function, "--callgrind-out-file=" + out.name] + command,
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        counts, calls = parse(out.name, function)
    if calls == 0:
        sys.exit("count_flops: no calls of " + function)
    flops = instructions = 0
    by_object = collections.Counter()
    for ob in {o for o, _ in counts}:
        code = disassemble(ob) if ob and ob.startswith("/") else {}
        for (o, addr), n in counts.items():
            if o != ob:
                continue
            instructions += n
            mnemonic, operands = code.get(addr, ("?", ""))
            f = flops_of(mnemonic, operands) * n
            flops += f
            by_object[ob] += f
    print(f"calls {calls}")
    print(f"flops per call {flops / calls:.6g}")
    print(f"instructions per call {instructions / calls:.6g}")
    for ob, f in by_object.most_common():
        print(f"  flops per call in {ob}: {f / calls:.6g}")


if __name__ == "__main__":
    main()
