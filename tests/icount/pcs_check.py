#!/usr/bin/env python3
"""The icount plugin's per-address mode (pcs=) and tools/icount-annotate against independent
references (tests/icount/CMakeLists.txt):

1. QEMU's own execution trace with one instruction per block (-singlestep -d exec,nochain: one
   "Trace" line per executed instruction, its guest PC in the second field of the brackets):
   the plugin's count at every address equals the trace's, and they sum to the total insns.
2. The same program run normally (multi-instruction blocks): the same per-address file.
3. icount_probe's kernel, whose count is known from its assembly (icount_probe.cpp): 10 calls
   of 5 + 10 m instructions (the calling `bl` is main's), m executions of each loop
   instruction per call; tools/icount-annotate must attribute exactly that, and still so with
   a line it cannot read added to the file.

  pcs_check.py --emulator 'qemu-aarch64|-L|dir' --plugin libccmap_icount.so --probe icount_probe
               --annotate tools/icount-annotate --objdump aarch64-linux-gnu-objdump --work DIR
"""
import argparse
import collections
import os
import re
import shutil
import subprocess
import sys

M = 3  # kernel iterations per call
CALLS = 10  # calls of the kernel in icount_probe without `errors`


def fail(message):
    print(f"pcs_check: FAIL {message}")
    sys.exit(1)


def run(emulator, plugin, probe, work, label, extra):
    out = os.path.join(work, f"{label}.icount")
    pcs = os.path.join(work, f"{label}.pcs")
    subprocess.run(emulator + extra + ["-plugin", f"{plugin},out={out},pcs={pcs}", probe, str(M)],
                   check=True, stdout=subprocess.DEVNULL)
    with open(out, encoding="ascii") as f:
        m = re.search(r"^total insns=(\d+) ", f.read(), re.M)
    if not m:
        fail(f"no total in {out}")
    counts = {}
    with open(pcs, encoding="ascii") as f:
        text = f.read()
    for line in text.splitlines():
        if not line.startswith("#"):
            address, n = line.split()
            counts[int(address, 16)] = int(n)
    if not re.search(r"^# addresses=\d+ dropped=0$", text, re.M):
        fail(f"{pcs}: no trailer, or addresses dropped")
    return int(m.group(1)), counts, pcs


def main():
    parser = argparse.ArgumentParser()
    for name in ("emulator", "plugin", "probe", "annotate", "objdump", "work"):
        parser.add_argument(f"--{name}", required=True)
    args = parser.parse_args()
    emulator = args.emulator.split("|")
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)

    trace_log = os.path.join(args.work, "trace.log")
    total, single, pcs = run(emulator, args.plugin, args.probe, args.work, "singlestep",
                             ["-singlestep", "-d", "exec,nochain", "-D", trace_log])
    traced = collections.Counter()
    with open(trace_log, encoding="ascii", errors="replace") as f:
        for line in f:
            if line.startswith("Trace "):
                traced[int(re.search(r"\[[0-9a-f]+/([0-9a-f]+)/", line).group(1), 16)] += 1
    if sum(single.values()) != total:
        fail(f"per-address counts sum to {sum(single.values())}, the total is {total}")
    if dict(traced) != single:
        differ = [a for a in set(traced) | set(single) if traced.get(a, 0) != single.get(a, 0)]
        fail(f"{len(differ)} addresses differ from QEMU's trace, e.g. {differ[0]:#x}: "
             f"trace {traced.get(differ[0], 0)}, plugin {single.get(differ[0], 0)}")
    print(f"pcs_check: {len(single)} addresses, {total} executions: equal to QEMU's trace")

    _, normal, _ = run(emulator, args.plugin, args.probe, args.work, "normal", [])
    if normal != single:
        fail("the per-address counts differ between the normal and the single-step run")
    print("pcs_check: the same per-address counts with normal blocks")

    # The annotator, on the file as written and with a line it cannot read beside the good ones.
    damaged = os.path.join(args.work, "damaged.pcs")
    with open(pcs, encoding="ascii") as f, open(damaged, "w", encoding="ascii") as g:
        lines = f.readlines()
        g.writelines(lines[:3] + ["0xnot-an-address 12\n"] + lines[3:])
    expected_kernel = CALLS * (5 + 10 * M)
    for path, warning in ((pcs, False), (damaged, True)):
        result = subprocess.run([args.annotate, args.probe, path, "--objdump", args.objdump, "--function",
                                 "ccmap_icount_probe_kernel"], check=True, capture_output=True, text=True)
        m = re.search(r"^# ccmap_icount_probe_kernel \(0x[0-9a-f]+\): (\d+) executions$", result.stdout, re.M)
        if not m or int(m.group(1)) != expected_kernel:
            fail(f"{path}: the kernel's executions are not {expected_kernel}:\n{result.stdout}")
        # Per instruction, in address order: 4 of set-up once per call, 10 of the loop m times, ret.
        listed = [int(n) for n in re.findall(r"^\s+(\d+)\s+[0-9a-f]+:\s", result.stdout.split("# ccmap_icount")[1], re.M)]
        if listed != [CALLS] * 4 + [CALLS * M] * 10 + [CALLS]:
            fail(f"{path}: per instruction {listed}, not 4 x {CALLS}, 10 x {CALLS * M}, 1 x {CALLS}")
        if warning != ("1 line(s)" in result.stderr):
            fail(f"{path}: the warning about the unreadable line is {'missing' if warning else 'unexpected'}")
    print(f"pcs_check: icount-annotate gives the kernel {expected_kernel} executions, "
          f"{CALLS * M} per loop instruction, with and without an unreadable line")


if __name__ == "__main__":
    main()
