#!/usr/bin/env python3
"""Run `cisamr mesh ... --report R.json` and attribute its resident memory to the phases.

    mesh_memory.py [--limit-gib G] [--interval S] -- CISAMR mesh SCENE -o OUT --report R.json [-v ...]

Samples the process's VmRSS every --interval seconds (default 0.2) from /proc, reads the
peak (VmHWM) and the kernel's max RSS at the end, and places the samples in the phases of
the report's timings_s (the time before the first phase is "read + oracle + levels"). Prints
the command's own output, then one line per phase: seconds, peak RSS sampled in it, RSS at
its end. With --limit-gib the command runs under an address-space limit (RLIMIT_AS), so a
run that would not fit fails with std::bad_alloc instead of pushing the machine into the
OOM killer. Linux only.
"""
import json
import resource
import subprocess
import sys
import time


def main():
    args = sys.argv[1:]
    limit_gib, interval = None, 0.2
    while args and args[0] != "--":
        if args[0] == "--limit-gib":
            limit_gib = float(args[1])
            args = args[2:]
        elif args[0] == "--interval":
            interval = float(args[1])
            args = args[2:]
        else:
            sys.exit(__doc__)
    command = args[1:]
    if not command or "--report" not in command:
        sys.exit(__doc__)
    report = command[command.index("--report") + 1]

    def limit():
        if limit_gib:
            cap = int(limit_gib * 2**30)
            resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    start = time.monotonic()
    proc = subprocess.Popen(command, preexec_fn=limit)
    samples = []  # (seconds since start, RSS KiB)
    hwm = 0
    while proc.poll() is None:
        try:
            with open(f"/proc/{proc.pid}/status") as status:
                for line in status:
                    if line.startswith("VmRSS:"):
                        samples.append((time.monotonic() - start, int(line.split()[1])))
                    elif line.startswith("VmHWM:"):
                        hwm = max(hwm, int(line.split()[1]))
        except (FileNotFoundError, ProcessLookupError):
            break
        time.sleep(interval)
    code = proc.wait()
    wall = time.monotonic() - start
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    maxrss = usage.ru_maxrss  # KiB on Linux
    print(f"exit status {code}, wall {wall:.1f} s, CPU {usage.ru_utime + usage.ru_stime:.1f} s, "
          f"peak RSS {max(hwm, maxrss) / 2**20:.2f} GiB ({max(hwm, maxrss)} KiB)")
    if code not in (0, 3):
        return code
    with open(report) as f:
        r = json.load(f)
    phases = [(name, t["max"]) for name, t in r["timings_s"].items() if name != "total"]
    # timings_s is a JSON object: restore the pipeline's order.
    order = ["samr", "radapt", "faceswap", "subdivide", "assemble", "quality", "write"]
    phases.sort(key=lambda p: order.index(p[0]) if p[0] in order else len(order))
    before = max(0.0, r["total_s"] - sum(s for _, s in phases))
    windows, t = [("read + oracle + levels", 0.0, before)], before
    for name, s in phases:
        windows.append((name, t, t + s))
        t += s
    windows.append(("report + exit", t, wall + 1))
    tets = r["elements"]
    print(f"{tets} tets, {r['nodes']} nodes, total_s {r['total_s']:.1f}, "
          f"{max(hwm, maxrss) * 1024 / tets:.0f} bytes/tet at the peak")
    print(f"{'phase':<24} {'s':>8} {'peak RSS in phase (GiB)':>24} {'RSS at end (GiB)':>17}")
    for name, a, b in windows:
        inside = [kb for (ts, kb) in samples if a <= ts < b]
        peak = max(inside) / 2**20 if inside else float("nan")
        last = inside[-1] / 2**20 if inside else float("nan")
        print(f"{name:<24} {b - a if name != 'report + exit' else wall - a:8.2f} {peak:24.2f} {last:17.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
