#!/usr/bin/env bash
# Peer comparison: kshell against the discrete-shell library libshell (evouga/libshell), as time
# to reach 1e-3 relative error on two problems with known answers (README.md beside this file).
# Writes paper_repro/peer/results.txt (the README's tables come from it) and the raw timings
# paper_repro/peer/raw.csv.
#
# Needs:
#  * libshell at commit 6072d9e4b3c9f99c8cfe538b8b5560954d87dfdf, out of this repository:
#        git clone https://github.com/evouga/libshell /tmp/libshell
#        git -C /tmp/libshell checkout 6072d9e4b3c9f99c8cfe538b8b5560954d87dfdf
#        LIBSHELL_DIR=/tmp/libshell bash paper_repro/peer/run.sh
#    (libshell's own CMake build wants CMake >= 4.0 and downloads libigl and polyscope for its
#    viewer example; the library itself needs only Eigen, so this script compiles its sources
#    directly, out of tree, under $BUILD_DIR.)
#  * Eigen 3 headers: Debian/Ubuntu `apt-get install libeigen3-dev` (/usr/include/eigen3, used
#    here: 3.4.0), or an Eigen 3 source tree given as EIGEN_DIR.
#  * g++ (C++17), Python 3 (summarise.py: medians and tables), and a Rust toolchain for kshell.
#
# Settings (environment): LIBSHELL_DIR (required), EIGEN_DIR (default /usr/include/eigen3),
# BUILD_DIR (default /tmp/kshell-peer-build), REPS (runs per measurement, default 3),
# CXXFLAGS (default -O3 -DNDEBUG; kshell is built with Cargo's release profile, no
# target-cpu=native, so neither is the C++).
#
# Run it on a quiet machine: every measurement is wall-clock time.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
: "${LIBSHELL_DIR:?set LIBSHELL_DIR to a libshell checkout (see the top of this script)}"
EIGEN_DIR="${EIGEN_DIR:-/usr/include/eigen3}"
BUILD_DIR="${BUILD_DIR:-/tmp/kshell-peer-build}"
REPS="${REPS:-3}"
CXXFLAGS="${CXXFLAGS:--O3 -DNDEBUG}"
CXX="${CXX:-g++}"

case "$(cd "$BUILD_DIR" 2>/dev/null && pwd || echo "$BUILD_DIR")/" in
"$ROOT"/*) echo "BUILD_DIR must be outside the repository" >&2; exit 1 ;;
esac
[ -f "$EIGEN_DIR/Eigen/Core" ] || { echo "no Eigen at EIGEN_DIR=$EIGEN_DIR (apt-get install libeigen3-dev)" >&2; exit 1; }
[ -f "$LIBSHELL_DIR/include/ElasticShell.h" ] || { echo "no libshell at LIBSHELL_DIR=$LIBSHELL_DIR" >&2; exit 1; }
mkdir -p "$BUILD_DIR/obj"

# ---- build libshell (library sources only) and the driver, out of tree ----------------------
echo "building libshell and the driver in $BUILD_DIR ..." >&2
srcs=("$LIBSHELL_DIR"/src/*.cpp "$LIBSHELL_DIR"/src/SecondFundamentalForm/*.cpp "$LIBSHELL_DIR"/src/MaterialModel/*.cpp)
objs=()
todo=()
for s in "${srcs[@]}"; do
    o="$BUILD_DIR/obj/$(basename "$(dirname "$s")")_$(basename "${s%.cpp}").o"
    objs+=("$o")
    if [ ! -f "$o" ] || [ "$s" -nt "$o" ]; then todo+=("$s" "$o"); fi
done
# (a few minutes on 2 cores: the derivative code is heavily templated)
printf '%s\n' "${todo[@]}" | xargs -r -P "$(nproc)" -n 2 \
    sh -c "$CXX -std=c++17 $CXXFLAGS -I'$EIGEN_DIR' -c \"\$0\" -o \"\$1\""
$CXX -std=c++17 $CXXFLAGS -I"$EIGEN_DIR" -I"$LIBSHELL_DIR/include" \
    "$HERE/libshell_driver.cpp" "${objs[@]}" -o "$BUILD_DIR/libshell_driver"
DRIVER="$BUILD_DIR/libshell_driver"
LIBSHELL_COMMIT="$(git -C "$LIBSHELL_DIR" rev-parse HEAD 2>/dev/null || echo "unknown (not a git checkout)")"

# ---- build kshell ---------------------------------------------------------------------------
echo "building kshell ..." >&2
(cd "$ROOT" && cargo build --release --bin ks-fit --examples --quiet)
KSFIT="$ROOT/target/release/ks-fit"
PLATES="$ROOT/target/release/examples/plates"

# ---- untimed: checks behind the choices in the driver (README, "libshell set-up") ------------
CHECKS="$BUILD_DIR/checks.txt"
{
    "$DRIVER" check
    echo "simply supported plate with the midedge-average formulation (for comparison):"
    for n in 8 16 32 64; do "$DRIVER" plate $n simple --sff average; done
    echo "clamped plate, ghost-face stiffness 1e4 instead of 1e6:"
    "$DRIVER" plate 64 clamped --ghost-stiffness 1e4
    echo "cantilever without the full-step start (line-searched Newton, then load steps):"
    "$DRIVER" cantilever 8 16 --full-steps 0
} > "$CHECKS"

# ---- timed runs -----------------------------------------------------------------------------
RAW="$HERE/raw.csv"
echo "code,problem,mesh,threads,rep,qoi,rel_error,seconds,iterations,internal_seconds,dofs" > "$RAW"
diff_s() { awk -v a="$1" -v b="$2" 'BEGIN{printf "%.6f", a - b}'; }
uptime > "$BUILD_DIR/load_before.txt"

# Heavy cantilever. Overhang = 2 x bending length c = (E t^3 / 12 / (rho g))^(1/3) = 23.86745 mm
# (exact chord angle 41.4873 degrees). Seconds: the whole process, wall clock, for both codes
# (the driver's own set-up + solve clock is kept as internal_seconds).
OVERHANG=47.7349
for rep in $(seq 1 "$REPS"); do
    for threads in 2 1; do
        for n in 8 16 32 64; do
            t0=$EPOCHREALTIME
            out=$(RAYON_NUM_THREADS=$threads "$KSFIT" bend --material "$HERE/heavy.toml" --angle 90 \
                --overhang $OVERHANG --mesh 4x$n -v 2>"$BUILD_DIR/ks.err" | tail -1)
            t1=$EPOCHREALTIME
            it=$(sed -n 's/.* \([0-9]*\) iterations in all.*/\1/p' "$BUILD_DIR/ks.err")
            echo "kshell,cantilever,4x$n,$threads,$rep,${out#*,},,$(diff_s "$t1" "$t0"),$it,," >> "$RAW"
        done
    done
    for mesh in "4 8" "8 16" "16 32" "32 64" "4 16" "4 32" "4 64"; do
        set -- $mesh
        t0=$EPOCHREALTIME
        line=$("$DRIVER" cantilever "$1" "$2")
        t1=$EPOCHREALTIME
        IFS=, read -r _ m _ dofs qoi err _ it setup solve <<< "$line"
        internal=$(awk -v a="$setup" -v b="$solve" 'BEGIN{printf "%.6f", a + b}')
        echo "libshell,cantilever,$m,1,$rep,$qoi,$err,$(diff_s "$t1" "$t0"),$it,$internal,$dofs" >> "$RAW"
    done
done

# Square plates. kshell: the plates example solves n = 4 ... 64 for both supports in one
# process and prints a line after each solve (Rust's stdout is line-buffered), so a solve's
# time is the time between its line and the line before it (model set-up and solve; process
# start excluded). libshell: the driver's own clock, set-up plus solve.
for rep in $(seq 1 "$REPS"); do
    for threads in 2 1; do
        # time-stamp each line as it arrives (shell built-ins only: no process started here)
        stamps="$BUILD_DIR/plates.stamps"
        : > "$stamps"
        echo "$EPOCHREALTIME start" >> "$stamps"
        while IFS= read -r line; do
            echo "$EPOCHREALTIME $line" >> "$stamps"
        done < <(RAYON_NUM_THREADS=$threads "$PLATES")
        awk -v th="$threads" -v rep="$rep" '
            NR == 1 { prev = $1; next }
            $2 ~ /^Simple/ { support = "plate_simple" }
            $2 ~ /^Clamped/ { support = "plate_clamped" }
            $2 ~ /^[0-9]+$/ { printf "kshell,%s,%sx%s,%s,%s,%s,%s,%.6f,,,%s\n", support, $2, $2, th, rep, $4, $5, $1 - prev, $3 }
            { prev = $1 }' "$stamps" >> "$RAW"
    done
    for support in simple clamped; do
        ns="4 8 16 32 64 128"
        [ $support = clamped ] && ns="$ns 256"
        for n in $ns; do
            line=$("$DRIVER" plate "$n" "$support")
            IFS=, read -r p m _ dofs qoi err _ it setup solve <<< "$line"
            internal=$(awk -v a="$setup" -v b="$solve" 'BEGIN{printf "%.6f", a + b}')
            echo "libshell,$p,$m,1,$rep,$qoi,$err,$internal,$it,$internal,$dofs" >> "$RAW"
        done
    done
done
uptime > "$BUILD_DIR/load_after.txt"

# ---- medians and tables ---------------------------------------------------------------------
python3 "$HERE/summarise.py" "$RAW" "$CHECKS" "$BUILD_DIR/load_before.txt" "$BUILD_DIR/load_after.txt" \
    "$LIBSHELL_COMMIT" "$(git -C "$ROOT" rev-parse --short HEAD)" "$CXX $CXXFLAGS" > "$HERE/results.txt"
cat "$HERE/results.txt"
