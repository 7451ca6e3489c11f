#!/usr/bin/env bash
# Where a fit's time goes, by kernel: samples each bundled fabric's default fit with `perf
# record` (self time per function, 999 Hz, every thread) and groups the functions into the
# kernels of docs/design.md, written to profile.md. Needs Linux perf; the release build keeps
# its symbols. The stage times come with every fit ([fit.stage_seconds]; summary.md).
#
#   bash paper_repro/fit_speed/profile.sh [FABRIC ...]      # default: all five
set -euo pipefail
cd "$(dirname "$0")/../.."
command -v perf >/dev/null || { echo "profile.sh: needs Linux perf"; exit 1; }
cargo build --release --bin ks-fit
out=paper_repro/fit_speed
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fabrics=("$@")
[ ${#fabrics[@]} -gt 0 ] || fabrics=(cotton silk wool denim canvas)
for f in "${fabrics[@]}"; do
  perf record -q -F 999 -o "$work/$f.data" target/release/ks-fit fit \
    "paper_repro/fabrics/$f/fabric.toml" -o "$work/$f.toml" >/dev/null 2>&1
  perf report -i "$work/$f.data" --no-children --sort symbol --stdio 2>/dev/null \
    | awk '/^ +[0-9.]+%/ { p = $1; sub(/%/, "", p); $1 = ""; print p "\t" $0 }' \
    > "$work/$f.tsv"
done
python3 - "$work" "${fabrics[@]}" > "$out/profile.md" <<'EOF'
import sys, re, tomllib
work, fabrics = sys.argv[1], sys.argv[2:]
fits = {f: tomllib.load(open(f"{work}/{f}.toml", "rb"))["fit"] for f in fabrics}
# kernel: patterns on the demangled function name, first match wins
KERNELS = [
    ("kernel (scheduling, page faults)", r"^\[k\]"),
    ("material law: η and its derivatives (expm1, ln1p)", r"kshell::material::|expm1|log1p|__exp|__log|__pow"),
    ("sensitivities (∂forces/∂parameters)", r"kshell::assembly::sensitivities"),
    ("assembly: Gauss-point kinematics, strains, element forces and Hessians",
     r"kshell::(assembly|shell|subdiv)::|nalgebra::"),
    ("sparse Cholesky: analysis, factorisation, solves", r"faer|gemm|pulp|equator|dyn_stack"),
    ("extended-precision residual refinement", r"kshell::solve::refine|__gmp|mpfr|rug::"),
    ("Newton, line searches, system bookkeeping", r"kshell::solve::"),
    ("homogeneous-strip bootstrap and space mapping", r"kshell::fit::(bootstrap|surrogate)"),
    ("memory: allocation, copies, zeroing", r"malloc|free|calloc|realloc|memset|memmove|memcpy|cfree"),
]
cols = {}
for f in fabrics:
    share = {k: 0.0 for k, _ in KERNELS}
    share["other"] = 0.0
    for line in open(f"{work}/{f}.tsv"):
        p, name = line.rstrip("\n").split("\t", 1)
        name = name.strip()
        for k, pat in KERNELS:
            if re.search(pat, name):
                share[k] += float(p)
                break
        else:
            share["other"] += float(p)
    cols[f] = share
print("# Where a fit's time goes, by kernel\n")
print("Made by `bash paper_repro/fit_speed/profile.sh`: `perf record` at 999 Hz over each bundled")
print("fabric's default `ks-fit fit`, self time per function grouped by kernel, in % of the samples")
print("(every thread). A function inlined into another counts as the caller's: the face loop's")
print("share includes the law's inlined parts.\n")
print("| kernel | " + " | ".join(fabrics) + " |")
print("|---|" + "---|" * len(fabrics))
for k in [k for k, _ in KERNELS] + ["other"]:
    print(f"| {k} | " + " | ".join(f"{cols[f][k]:.1f}" for f in fabrics) + " |")
print("\n## By stage\n")
print("Share of each fit's stage time in the same runs (`[fit.stage_seconds]`), in %. Timings")
print("themselves are in summary.md and before_after.md (paired runs on a quiet machine).\n")
print("| stage | " + " | ".join(fabrics) + " |")
print("|---|" + "---|" * len(fabrics))
stages = list(dict.fromkeys(k for f in fabrics for k in fits[f]["stage_seconds"]))
total = {f: sum(fits[f]["stage_seconds"].values()) for f in fabrics}
for k in stages:
    print(f"| {k} | " + " | ".join(f"{100 * fits[f]['stage_seconds'].get(k, 0.0) / total[f]:.1f}" for f in fabrics) + " |")
EOF
echo "wrote $out/profile.md"
