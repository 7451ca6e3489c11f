"""Tables of paper_repro/peer/run.sh: medians of the timed runs, errors against the exact
values, time to reach 1e-3 relative error and the libshell / kshell ratios.

Usage: summarise.py raw.csv checks.txt load_before.txt load_after.txt libshell_commit kshell_commit compiler
"""
import csv
import os
import platform
import statistics
import sys

raw, checks, load0, load1, lcommit, kcommit, compiler = sys.argv[1:]
EXACT = {"cantilever": 41.4873, "plate_simple": 0.0040623527, "plate_clamped": 0.001265319}
QOI = {
    "cantilever": "chord angle (deg)",
    "plate_simple": "w_c D/(q a^4)",
    "plate_clamped": "w_c D/(q a^4)",
}
TOL = 1e-3  # the comparison's tolerance
TOLS = [TOL, 1e-4]  # 1e-4: secondary, for context
# refinement sequences, coarse to fine (each code's time to 1e-3 is that of its fastest sequence)
SEQUENCES = {
    ("cantilever", "kshell"): {"4 x N": ["4x8", "4x16", "4x32", "4x64"]},
    ("cantilever", "libshell"): {
        "N x 2N (near-square cells)": ["4x8", "8x16", "16x32", "32x64"],
        "4 x N": ["4x8", "4x16", "4x32", "4x64"],
    },
}
for p in ["plate_simple", "plate_clamped"]:
    SEQUENCES[(p, "kshell")] = {"N x N": [f"{n}x{n}" for n in [4, 8, 16, 32, 64]]}
    SEQUENCES[(p, "libshell")] = {"N x N": [f"{n}x{n}" for n in [4, 8, 16, 32, 64, 128, 256]]}

rows = list(csv.DictReader(open(raw)))
data = {}  # (problem, code, threads) -> mesh -> [rows]
for r in rows:
    data.setdefault((r["problem"], r["code"], r["threads"]), {}).setdefault(r["mesh"], []).append(r)

try:
    cpu = [l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")][0]
except (OSError, IndexError):
    cpu = "unknown CPU"

out = []
w = out.append
w(f"kshell {kcommit} against libshell {lcommit} (driver built with {compiler})")
w(f"machine: {os.cpu_count()} cores, {cpu}; {platform.platform()}")
w(f"load before the timed runs: {open(load0).read().strip()}")
w(f"load after the timed runs:  {open(load1).read().strip()}")
w("seconds: median of the runs (wall clock). Cantilever: the whole process, both codes.")
w("Plates: set-up + solve (kshell: time between the plates example's output lines; libshell: the driver's clock).")
w("free DOFs: unknowns of the solve (libshell: vertex coordinates and edge director angles; kshell: control-point")
w("coordinates, as its plates example prints them; ks-fit bend does not print them).")
w("'within TOL from M': the coarsest mesh M of a sequence from which on every finer mesh has |rel. error| <= TOL.")
w("")
w("== checks (untimed) ==")
w(open(checks).read().rstrip())


def stats(problem, code, threads, mesh):
    rs = data.get((problem, code, threads), {}).get(mesh)
    if not rs:
        return None
    q = float(rs[0]["qoi"])
    qs = {round(float(r["qoi"]), 9) for r in rs}
    # the code's own relative error where it prints one (full precision), else from the qoi
    err = float(rs[0]["rel_error"]) if rs[0]["rel_error"] else q / EXACT[problem] - 1
    return {
        "qoi": q,
        "err": err,
        "sec": statistics.median(float(r["seconds"]) for r in rs),
        "internal": statistics.median(float(r["internal_seconds"]) for r in rs) if rs[0]["internal_seconds"] else None,
        "it": rs[0]["iterations"] or "-",
        "dofs": rs[0]["dofs"] or "-",
        "runs": len(rs),
        "same": len(qs) == 1,
    }


reach = {}
for problem in ["cantilever", "plate_simple", "plate_clamped"]:
    w("")
    w(f"== {problem}: {QOI[problem]}, exact {EXACT[problem]} ==")
    for code, threads in [("kshell", "2"), ("kshell", "1"), ("libshell", "1")]:
        if (problem, code, threads) not in data:
            continue
        w(f"-- {code}, {threads} thread(s) --")
        internal = code == "libshell" and problem == "cantilever"
        w(f"{'mesh':<8} {'free DOFs':>9} {'qoi':>14} {'rel. error':>11} {'seconds':>9}"
          + (f" {'(in-process)':>12}" if internal else "") + f" {'Newton it.':>10} runs")
        listed = []
        for seq in SEQUENCES[(problem, code)].values():
            listed += [m for m in seq if m not in listed]
        for m in listed:
            s = stats(problem, code, threads, m)
            if s is None:
                continue
            line = f"{m:<8} {s['dofs']:>9} {s['qoi']:>14.9g} {s['err']:>11.3e} {s['sec']:>9.4f}"
            if internal:
                line += f" {s['internal']:>12.4f}"
            line += f" {s['it']:>10} {s['runs']}" + ("" if s["same"] else "  (qoi differs between runs!)")
            w(line)
        for tol in TOLS:
            for name, seq in SEQUENCES[(problem, code)].items():
                st = [(m, stats(problem, code, threads, m)) for m in seq]
                st = [(m, s) for m, s in st if s]
                hit = None
                for i, (m, s) in enumerate(st):
                    if all(abs(t["err"]) <= tol for _, t in st[i:]):
                        hit = (m, s)
                        break
                if hit:
                    m, s = hit
                    w(f"   {name}: within {tol:g} from {m} (error {s['err']:.2e}), {s['sec']:.4f} s")
                    best = reach.get((tol, problem, code, threads))
                    if best is None or s["sec"] < best[1]["sec"]:
                        reach[(tol, problem, code, threads)] = (m, s)
                else:
                    w(f"   {name}: not within {tol:g} on the meshes run")

for tol in TOLS:
    w("")
    w(f"== time to {tol:g} relative error (each code's fastest sequence)"
      + (" ==" if tol == TOL else ": secondary, for context ==") )
    w(f"{'problem':<14} {'kshell, 2 threads':>22} {'kshell, 1 thread':>22} {'libshell, 1 thread':>22}"
      f" {'ratio (2 thr)':>13} {'ratio (1 thr)':>13}")
    for problem in ["cantilever", "plate_simple", "plate_clamped"]:
        k2, k1, l1 = (reach.get((tol, problem, c, t)) for c, t in [("kshell", "2"), ("kshell", "1"), ("libshell", "1")])

        def cell(h):
            return f"{h[0]} {h[1]['sec']:.4f} s" if h else "not reached"

        def ratio(a, b):
            return f"{a[1]['sec'] / b[1]['sec']:.2f}" if (a and b) else "-"

        w(f"{problem:<14} {cell(k2):>22} {cell(k1):>22} {cell(l1):>22} {ratio(l1, k2):>13} {ratio(l1, k1):>13}")
w("ratio = libshell time / kshell time (above 1: kshell reaches the tolerance sooner)")
print("\n".join(out))
