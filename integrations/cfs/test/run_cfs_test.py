#!/usr/bin/env python3
"""ccmap_app in a running cFE: builds cFS 7.0.0 with the app, boots core-cpu1, commands it over
ci_lab (UDP 1234), reads its housekeeping and events from to_lab (UDP 1235) and checks it.

    integrations/cfs/test/run_cfs_test.py      (./tools/test cfs runs it)

The cFS sources: the package folder ../shared/cfs (cfs-7.0.0-src.tar.gz + startup-names.patch,
../shared/cfs/README.md), or CCMAP_CFS_DIR naming that folder or an extracted cFS tree. Without
them it says why and exits 0. The mission is built under build/cfs-test (extracted once; later
runs rebuild incrementally). Checks, each against the app's own telemetry and events:
  - counters move as frames go in (frames, points = 552,500 a frame, observed cells);
  - a malformed command (wrong length, unknown code) and a forged FRAME_READY are refused,
    each with its event, and counted;
  - a parameter table the library refuses (LOAD_TABLE) is refused with its events and the old one
    is kept (parameters and map unchanged); a good one is applied without wiping the map;
  - SAVE, CLEAR, LOAD gives the same map back: the product's cell CRC equal before and after,
    different after CLEAR, and a second SAVE byte-identical to the first; a damaged snapshot
    is refused and changes nothing;
  - every frame's handling stays under the table's cycle budget (80 ms).
cFE is stopped and only the SysV shared-memory segments this run created are removed, also on
failure. Runs as the unprivileged user "nobody" (setpriv) when started as root. Before all that
it runs the ground module's own tests (ground/test_ccmap_ground.py), and, where the aarch64 cross
compiler and QEMU are installed, counts the app's own frame handling (frame_icount.c) and checks
the ground module's packet formats against the aarch64 structs.
"""
import os
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
GROUND = os.path.join(REPO, "integrations", "cfs", "ground")
sys.path.insert(0, GROUND)
sys.dont_write_bytecode = True  # nothing written into the source tree
import ccmap_ground as g  # noqa: E402

FRAMES = 6
# The app's own code per frame (frame_icount.c, aarch64 -O2): measured 236 instructions; a copy
# of the frame's 6.6 MB alone would cost over a million.
FRAME_ICOUNT_BOUND = 1000
POINTS_PER_FRAME = 850 * 650
APPS_DIR = os.path.join(REPO, "integrations", "cfs")


class Failure(Exception):
    pass


def log(msg):
    print(f"cfs: {msg}", flush=True)


def find_sources():
    """(kind, path): ("package", folder with the tarball) or ("tree", an extracted cFS tree)."""
    given = os.environ.get("CCMAP_CFS_DIR")
    folder = os.path.abspath(given) if given else os.path.abspath(os.path.join(REPO, "..", "shared", "cfs"))
    if os.path.isfile(os.path.join(folder, "cfs-7.0.0-src.tar.gz")):
        return "package", folder
    if os.path.isdir(os.path.join(folder, "cfe")) and os.path.isdir(os.path.join(folder, "osal")):
        return "tree", folder
    return None, folder


def run(cmd, cwd, logfile, env=None):
    with open(logfile, "ab") as out:
        rc = subprocess.call(cmd, cwd=cwd, stdout=out, stderr=subprocess.STDOUT, env=env)
    if rc != 0:
        with open(logfile, "rb") as f:
            tail = f.read()[-4000:].decode(errors="replace")
        raise Failure(f"{' '.join(cmd)} failed ({rc}); end of {logfile}:\n{tail}")


def insert_after(path, anchor, text):
    with open(path) as f:
        content = f.read()
    if text in content:
        return
    if anchor not in content:
        raise Failure(f"{path}: '{anchor}' not found")
    with open(path, "w") as f:
        f.write(content.replace(anchor, anchor + text, 1))


def prepare_tree(kind, source, work):
    """The mission tree in work/cFS, set up once (the stamp file records it)."""
    tree = os.path.join(work, "cFS")
    stamp = os.path.join(work, "prepared")
    if os.path.exists(stamp):
        return tree
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    logfile = os.path.join(work, "setup.log")
    if kind == "package":
        run(["tar", "-xzf", os.path.join(source, "cfs-7.0.0-src.tar.gz")], work, logfile)
    else:
        # An extracted tree set up as ../shared/cfs/README.md says (its sample_defs patched).
        shutil.copytree(source, tree, symlinks=True, ignore=shutil.ignore_patterns("build"))
    shutil.copy(os.path.join(tree, "cfe", "cmake", "Makefile.sample"), os.path.join(tree, "Makefile"))
    if not os.path.isdir(os.path.join(tree, "sample_defs")):
        shutil.copytree(os.path.join(tree, "cfe", "cmake", "sample_defs"), os.path.join(tree, "sample_defs"))
    patch = os.path.join(source, "startup-names.patch")
    if kind == "package" and os.path.isfile(patch):
        run(["patch", "-p1", "-i", patch], tree, logfile)
    defs = os.path.join(tree, "sample_defs")
    # The app, its frame buffers and the test's producer on cpu1.
    insert_after(os.path.join(defs, "targets.cmake"), "SET(cpu1_APPLIST ci_lab to_lab sch_lab",
                 " ccmap_frames ccmap_app ccmap_feed")
    startup = os.path.join(defs, "cpu1_cfe_es_startup.scr")
    with open(startup) as f:
        lines = f.read().split("\n")
    bang = next(i for i, line in enumerate(lines) if line.startswith("!"))
    lines[bang:bang] = [
        "CFE_LIB, ccmap_frames, CCMAP_FRAMES_Init, CCMAP_FRAMES, 0,  0,     0x0, 0;",
        "CFE_APP, ccmap_app,    CCMAP_APP_Main,    CCMAP_APP,   90, 65536, 0x0, 0;",
        "CFE_APP, ccmap_feed,   CCMAP_FEED_Main,   CCMAP_FEED,  95, 16384, 0x0, 0;",
    ]
    with open(startup, "w") as f:
        f.write("\n".join(lines))
    # to_lab forwards the app's telemetry; sch_lab wakes its housekeeping 4 times a second.
    os.makedirs(os.path.join(defs, "tables"), exist_ok=True)
    sub = os.path.join(defs, "tables", "to_lab_sub.c")
    sch = os.path.join(defs, "tables", "sch_lab_table.c")
    shutil.copy(os.path.join(tree, "apps", "to_lab", "fsw", "tables", "to_lab_sub.c"), sub)
    shutil.copy(os.path.join(tree, "apps", "sch_lab", "fsw", "tables", "sch_lab_table.c"), sch)
    insert_after(sub, "{CFE_SB_MSGID_WRAP_VALUE(TO_LAB_HK_TLM_MID), {0, 0}, 4},",
                 "\n{CFE_SB_MSGID_WRAP_VALUE(0x08A1), {0, 0}, 4},"
                 "\n{CFE_SB_MSGID_WRAP_VALUE(0x08A3), {0, 0}, 4},")
    insert_after(sch, ".Config   = {", "\n{CFE_SB_MSGID_WRAP_VALUE(0x18A1), 25, 0},")
    open(stamp, "w").close()
    return tree


def build(tree, work):
    env = dict(os.environ, CFS_APP_PATH=APPS_DIR)
    if shutil.which("ccache"):
        env.setdefault("CMAKE_C_COMPILER_LAUNCHER", "ccache")
        env.setdefault("CMAKE_CXX_COMPILER_LAUNCHER", "ccache")
    jobs = os.environ.get("CCMAP_JOBS", str(min(os.cpu_count() or 2, 4)))
    logfile = os.path.join(work, "build.log")
    if os.path.exists(logfile):
        os.remove(logfile)
    if not os.path.isdir(os.path.join(tree, "build")):
        run(["make", "SIMULATION=native", "prep"], tree, logfile, env)
    arch = os.path.join(tree, "build", "native", "default_cpu1")
    if os.path.isdir(arch):
        # Regenerate the cpu's build serially first: a changed CMake file (the library's) would
        # otherwise be regenerated by two of make's jobs at once, which races.
        run(["make", "cmake_check_build_system"], arch, logfile, env)
    run(["make", f"-j{jobs}"], tree, logfile, env)
    run(["make", "install"], tree, logfile, env)


def write_frames(work, cf):
    exe = os.path.join(work, "write_frames")
    src = os.path.join(HERE, "write_frames.cpp")
    if not os.path.exists(exe) or os.path.getmtime(exe) < os.path.getmtime(src):
        cxx = ["ccache", "g++"] if shutil.which("ccache") else ["g++"]
        run(cxx + ["-std=c++17", "-O2", "-ffp-contract=off", "-I", os.path.join(REPO, "include"),
                   "-I", os.path.join(REPO, "tests"), src, "-o", exe], work, os.path.join(work, "build.log"))
    run([exe, cf, str(FRAMES)], work, os.path.join(work, "build.log"))


def frame_icount(tree, work, results):
    """aarch64 instructions of the app's own frame handling (frame_icount.c) under QEMU with the
    project's counting plugin; skipped without the cross compiler or QEMU user mode."""
    if not (shutil.which("aarch64-linux-gnu-gcc") and shutil.which("qemu-aarch64")):
        log("icount: skipped (aarch64-linux-gnu-gcc or qemu-aarch64 missing: tools/install-deps cross)")
        return
    logfile = os.path.join(work, "icount.log")
    plugin_dir = os.path.join(REPO, "tools", "qemu-icount")
    plugin = os.path.join(work, "libccmap_icount.so")
    run(["gcc", "-shared", "-fPIC", "-O2", "-std=c11", os.path.join(plugin_dir, "icount_plugin.c"),
         os.path.join(plugin_dir, "a64_class.c"), "-o", plugin], work, logfile)
    # The app's include path as the mission build gives it (its flags file), plus its sources.
    flags = os.path.join(tree, "build", "native", "default_cpu1", "apps", "ccmap_app", "CMakeFiles",
                         "ccmap_app.dir", "flags.make")
    with open(flags) as f:
        includes = sorted({word for word in f.read().split() if word.startswith("-I")})
    app = os.path.join(APPS_DIR, "ccmap_app", "fsw", "src")
    sources = [os.path.join(HERE, "frame_icount.c"), os.path.join(app, "ccmap_app_frame.c"),
               os.path.join(app, "ccmap_app_dispatch.c"),
               os.path.join(APPS_DIR, "ccmap_frames", "fsw", "src", "ccmap_frames.c")]
    for opt in ("-O2", "-O0"):
        exe = os.path.join(work, f"frame_icount{opt}")
        out = os.path.join(work, f"frame_icount{opt}.txt")
        run(["aarch64-linux-gnu-gcc", "-std=c99", opt, "-Wall", "-Werror", "-D_LINUX_OS_", "-D_POSIX_OS_",
             "-D_XOPEN_SOURCE=600", f"-I{app}"] + includes + sources + ["-o", exe], work, logfile)
        printed = subprocess.run(["qemu-aarch64", "-L", "/usr/aarch64-linux-gnu", "-plugin", f"{plugin},out={out}",
                                  exe], cwd=work, capture_output=True, text=True)
        if printed.returncode != 0:
            raise Failure(f"{exe} failed ({printed.returncode}): {printed.stdout}{printed.stderr}")
        sizes = dict(item.split("=") for item in printed.stdout.split()[1:])
        expected = {"hk": struct.calcsize(g.HK_FORMAT), "product": struct.calcsize(g.PRODUCT_FORMAT),
                    "table": struct.calcsize(g.TABLE_FORMAT)}
        if {k: int(v) for k, v in sizes.items()} != expected:
            raise Failure(f"aarch64 payload sizes {sizes} differ from the ground module's {expected}")
        regions = {}
        with open(out) as f:
            for line in f:
                fields = dict(item.split("=", 1) for item in line.split() if "=" in item)
                if "region" in fields:
                    regions[fields["region"]] = fields
        results[f"icount{opt}"] = (int(regions["1"]["max_interval_insns"]), int(regions["2"]["max_interval_insns"]))
    frame, refused = results["icount-O2"]
    log(f"ok: the ground module's HK, product and table formats match the aarch64 structs ({expected})")
    log(f"icount: the app's own code per frame {frame} aarch64 instructions at -O2 "
        f"({results['icount-O0'][0]} at -O0, cFS's default debug build), a refused FRAME_READY {refused}")
    if frame > FRAME_ICOUNT_BOUND:
        raise Failure(f"the app's own frame handling costs {frame} instructions, over {FRAME_ICOUNT_BOUND}")


def shm_ids():
    out = subprocess.run(["ipcs", "-m"], capture_output=True, text=True).stdout
    ids = set()
    for line in out.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0].startswith("0x") and parts[1].isdigit():
            ids.add(parts[1])
    return ids


class Ground:
    """The test's view of the running app: every packet seen, newest HK, events."""

    def __init__(self):
        self.link = g.Link()
        self.hk = None
        self.events = []
        self.products = []

    def pump(self, timeout):
        kind, fields = self.link.receive(timeout)
        if kind == "hk":
            self.hk = fields
        elif kind == "event":
            self.events.append(fields)
            if fields["app"].startswith("CCMAP") or fields["app"] == "CFE_TBL":
                log(f"  event {fields['app']} {fields['id']}: {fields['text']}")
        elif kind == "product":
            self.products.append(fields)
        return kind

    def wait(self, what, predicate, timeout=10.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.pump(end - time.monotonic())
            if predicate():
                return
        raise Failure(f"timed out waiting for {what}; last HK: {self.hk}")

    def fresh_hk(self, predicate=lambda hk: True, what="housekeeping", timeout=10.0):
        """The first HK after this call that satisfies predicate."""
        self.hk = None
        self.wait(what, lambda: self.hk is not None and predicate(self.hk), timeout)
        return self.hk

    def event(self, app, event_id, since, timeout=10.0):
        def seen():
            return any(e["app"] == app and e["id"] == event_id for e in self.events[since:])
        self.wait(f"event {app} {event_id}", seen, timeout)

    def send(self, packet):
        self.link.send(packet)


def check(condition, message):
    if not condition:
        raise Failure(message)
    log(f"ok: {message}")


def product(ground, hk_before):
    """PUBLISH and the HK that reports it."""
    ground.send(g.ccmap_command(g.PUBLISH))
    return ground.fresh_hk(lambda hk: hk["ProductSequence"] > hk_before["ProductSequence"], "a new product")


def scenario(ground, cf, results):
    hk = ground.fresh_hk(lambda hk: hk["MapInitialised"] == 1, "the initialised map", timeout=20)
    check(hk["TableUpdates"] >= 1 and abs(hk["CoverageTau"] - 0.8) < 1e-6,
          f"map initialised from the default table (coverage_tau {hk['CoverageTau']:.3f})")

    # Frames in: counters move.
    for k in range(FRAMES):
        before = ground.hk
        ground.send(g.feed_command(f"/cf/frame{k}.bin"))
        hk = ground.fresh_hk(lambda hk: hk["FramesAccepted"] == before["FramesAccepted"] + 1,
                             f"frame {k} accepted", timeout=15)
        check(hk["PointsReceived"] == before["PointsReceived"] + POINTS_PER_FRAME and
              hk["PointsUsed"] > before["PointsUsed"] and hk["ObservedCells"] > 0,
              f"frame {k}: points {hk['PointsReceived']} received, {hk['PointsUsed']} used, "
              f"{hk['ObservedCells']} cells observed, {hk['LastFrameUs']} us (library {hk['LastLibraryUs']} us)")
        results.setdefault("frame_us", []).append(hk["LastFrameUs"])
        results.setdefault("library_us", []).append(hk["LastLibraryUs"])
    check(hk["MaxFrameUs"] < hk["CycleBudgetUs"] and hk["BudgetOverruns"] == 0,
          f"longest frame handling {hk['MaxFrameUs']} us < budget {hk['CycleBudgetUs']} us, no overrun")

    # Malformed commands: refused, each with its event, and counted.
    before = ground.fresh_hk()
    mark = len(ground.events)
    ground.send(g.command(g.CCMAP_CMD_MID, g.NOOP, b"\0\0\0\0"))        # NOOP with 4 stray bytes
    ground.event("CCMAP_APP", g.EID["LEN_ERR"], mark)
    ground.send(g.command(g.CCMAP_CMD_MID, 77))                          # no such code
    ground.event("CCMAP_APP", g.EID["CC_ERR"], mark)
    ground.send(g.command(g.CCMAP_FRAME_READY_MID, 0, bytes(8)))        # forged FRAME_READY: slot 0, seq 0
    ground.event("CCMAP_APP", g.EID["FRAME_ERR"], mark)
    hk = ground.fresh_hk(lambda hk: hk["CommandErrorCounter"] >= before["CommandErrorCounter"] + 2)
    check(hk["CommandErrorCounter"] == before["CommandErrorCounter"] + 2 and
          hk["FramesDropped"] == before["FramesDropped"] + 1 and
          hk["FramesAccepted"] == before["FramesAccepted"],
          "wrong length and unknown code refused and counted (CommandErrorCounter +2), "
          "forged FRAME_READY dropped (FramesDropped +1), no frame mapped")

    # A table the library refuses: its event, the old table and the map kept.
    with open(os.path.join(cf, "ccmap_app_tbl.tbl"), "rb") as f:
        template = f.read()
    with open(os.path.join(cf, "ccmap_bad.tbl"), "wb") as f:
        f.write(g.table_file(template, CoverageTau=1.5))
    with open(os.path.join(cf, "ccmap_good.tbl"), "wb") as f:
        f.write(g.table_file(template, CoverageTau=0.7))
    before = ground.fresh_hk()
    mark = len(ground.events)
    ground.send(g.ccmap_command(g.LOAD_TABLE, "/cf/ccmap_bad.tbl"))
    ground.event("CCMAP_APP", g.EID["TBL_VAL_ERR"], mark)
    ground.event("CCMAP_APP", g.EID["TBL_ERR"], mark)
    hk = ground.fresh_hk(lambda hk: hk["TableRefusals"] == before["TableRefusals"] + 1, "the table refusal")
    check(hk["TableUpdates"] == before["TableUpdates"] and abs(hk["CoverageTau"] - 0.8) < 1e-6 and
          hk["ParamsCrc"] == before["ParamsCrc"] and hk["ObservedCells"] == before["ObservedCells"] and
          hk["CommandErrorCounter"] == before["CommandErrorCounter"] + 1,
          "table with coverage_tau 1.5 refused by the library's validation (events 25, 26), counted; "
          "the old table, parameters and map kept")
    ground.send(g.ccmap_command(g.LOAD_TABLE, "/cf/ccmap_good.tbl"))
    hk = ground.fresh_hk(lambda hk: hk["TableUpdates"] == before["TableUpdates"] + 1, "the good table")
    check(abs(hk["CoverageTau"] - 0.7) < 1e-6 and hk["ParamsCrc"] != before["ParamsCrc"] and
          hk["ObservedCells"] == before["ObservedCells"] and hk["MapInitialised"] == 1,
          "table with coverage_tau 0.7 applied, the map kept (same observed cells)")

    # SAVE, CLEAR, LOAD: the same map back.
    for name in ("map1.snap", "map2.snap"):
        if os.path.exists(os.path.join(cf, name)):
            os.remove(os.path.join(cf, name))
    p1 = product(ground, ground.fresh_hk())
    ground.send(g.ccmap_command(g.SAVE, "/cf/map1.snap"))
    hk = ground.fresh_hk(lambda hk: hk["CommandCounter"] > p1["CommandCounter"], "SAVE")
    ground.send(g.ccmap_command(g.CLEAR))
    hk = ground.fresh_hk(lambda hk: hk["ObservedCells"] == 0, "CLEAR")
    p2 = product(ground, hk)
    check(p2["ProductCellsCrc"] != p1["ProductCellsCrc"],
          f"after CLEAR the product differs (cells CRC {p2['ProductCellsCrc']:08x} vs {p1['ProductCellsCrc']:08x})")
    snapshot = open(os.path.join(cf, "map1.snap"), "rb").read()
    damaged = bytearray(snapshot)
    damaged[len(damaged) // 2] ^= 0x40
    with open(os.path.join(cf, "damaged.snap"), "wb") as f:
        f.write(damaged)
    mark = len(ground.events)
    ground.send(g.ccmap_command(g.LOAD, "/cf/damaged.snap"))
    ground.event("CCMAP_APP", g.EID["SNAPSHOT_ERR"], mark)
    ground.send(g.ccmap_command(g.LOAD, "/cf/map1.snap"))
    hk = ground.fresh_hk(lambda hk: hk["ObservedCells"] == p1["ObservedCells"], "LOAD")
    p3 = product(ground, hk)
    check(p3["ProductCellsCrc"] == p1["ProductCellsCrc"] and p3["ObservedCells"] == p1["ObservedCells"],
          f"a damaged snapshot refused; SAVE, CLEAR, LOAD: the same product cells "
          f"(CRC {p3['ProductCellsCrc']:08x}, {p3['ObservedCells']} cells)")
    ground.send(g.ccmap_command(g.SAVE, "/cf/map2.snap"))
    ground.fresh_hk(lambda hk: hk["CommandCounter"] > p3["CommandCounter"], "second SAVE")
    again = open(os.path.join(cf, "map2.snap"), "rb").read()
    check(again == snapshot, f"the reloaded map saves byte-identical ({len(snapshot)} bytes)")

    # RESET_COUNTERS.
    ground.send(g.ccmap_command(g.RESET_COUNTERS))
    hk = ground.fresh_hk(lambda hk: hk["CommandErrorCounter"] == 0 and hk["FramesAccepted"] == 0, "reset")
    check(hk["MaxFrameUs"] == 0 and hk["ObservedCells"] == p1["ObservedCells"],
          "RESET_COUNTERS zeroes the counters, keeps the map")


def boot_and_test(tree, work, results):
    exe_dir = os.path.join(tree, "build", "exe", "cpu1")
    cf = os.path.join(exe_dir, "cf")
    t0 = time.monotonic()
    write_frames(work, cf)
    results["frames_s"] = time.monotonic() - t0
    for name in ("EEPROM.DAT", ".cdskeyfile", ".resetkeyfile", ".reservedkeyfile"):
        path = os.path.join(exe_dir, name)
        if os.path.exists(path):
            os.remove(path)
    cmd = ["./core-cpu1"]
    if os.geteuid() == 0:
        # Root in a container lacks CAP_SYS_RESOURCE for deep queues: run as nobody.
        subprocess.check_call(["chown", "-R", "nobody:nogroup", exe_dir])
        cmd = ["setpriv", "--reuid=nobody", "--regid=nogroup", "--clear-groups"] + cmd
    before = shm_ids()
    console = open(os.path.join(work, "core-cpu1.log"), "wb")
    proc = subprocess.Popen(cmd, cwd=exe_dir, stdout=console, stderr=subprocess.STDOUT, start_new_session=True)
    ground = None
    try:
        end = time.monotonic() + 30
        text = ""
        while "entering OPERATIONAL state" not in text:
            if time.monotonic() > end or proc.poll() is not None:
                raise Failure(f"cFE did not reach OPERATIONAL; console:\n{text[-3000:]}")
            time.sleep(0.2)
            with open(os.path.join(work, "core-cpu1.log"), "rb") as f:
                text = f.read().decode(errors="replace")
        results["boot_s"] = time.monotonic() - t0 - results["frames_s"]
        ground = Ground()
        end = time.monotonic() + 10
        while ground.hk is None:
            if time.monotonic() > end:
                raise Failure("no ccmap housekeeping on UDP 1235 after enabling to_lab")
            ground.send(g.enable_output())
            ground.pump(1.0)
        scenario(ground, cf, results)
    finally:
        if ground:
            ground.link.close()
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGTERM)
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
        console.close()
        for shmid in sorted(shm_ids() - before):
            subprocess.call(["ipcrm", "-m", shmid])
        left = shm_ids() - before
        if left:
            log(f"warning: shared-memory segments left: {sorted(left)}")


def main():
    # The ground module's own checks first: they need no cFS.
    if subprocess.call([sys.executable, "-B", "-m", "unittest", "-q", "test_ccmap_ground"], cwd=GROUND) != 0:
        log("FAILED: integrations/cfs/ground/test_ccmap_ground.py")
        return 1
    kind, source = find_sources()
    if kind is None:
        if os.environ.get("CCMAP_CFS_DIR"):
            log(f"skipped: CCMAP_CFS_DIR={source} holds neither cfs-7.0.0-src.tar.gz nor a cFS tree")
        else:
            log("skipped: ../shared/cfs not found (set CCMAP_CFS_DIR)")
        return 0
    for tool in ("make", "cmake", "gcc", "g++", "patch", "ipcs", "ipcrm"):
        if shutil.which(tool) is None:
            log(f"FAILED: {tool} not found")
            return 1
    if os.geteuid() == 0 and shutil.which("setpriv") is None:
        log("FAILED: running as root needs setpriv (util-linux) to start cFE as nobody")
        return 1
    work = os.path.join(REPO, "build", "cfs-test")
    results = {}
    start = time.monotonic()
    try:
        tree = prepare_tree(kind, source, work)
        t = time.monotonic()
        build(tree, work)
        results["build_s"] = time.monotonic() - t
        frame_icount(tree, work, results)
        t = time.monotonic()
        boot_and_test(tree, work, results)
        results["test_s"] = time.monotonic() - t
    except Failure as failure:
        log(f"FAILED: {failure}")
        log(f"logs: {work}/build.log, {work}/core-cpu1.log")
        return 1
    frame = results.get("frame_us", [0])
    lib = results.get("library_us", [0])
    log(f"frame handling {min(frame)}-{max(frame)} us, of which the library {min(lib)}-{max(lib)} us "
        f"(the app's own: {min(f - l for f, l in zip(frame, lib))}-{max(f - l for f, l in zip(frame, lib))} us)")
    log(f"ok: build {results['build_s']:.0f} s, frames {results['frames_s']:.1f} s, boot "
        f"{results['boot_s']:.1f} s, test {results['test_s']:.0f} s, total {time.monotonic() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
