#!/usr/bin/env bash
# Regenerates every convergence table and chart of paper_repro/convergence from the repository
# root: the accuracy-against-time chart, the plate, roof, balloon, heavy-cantilever and Sze cantilever sweeps,
# and ks-fit converge studies of the example material (tables, CSV, SVG).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=paper_repro/convergence
cargo build --release --examples --bin ks-fit
cargo run --release --example convergence_chart > "$out/accuracy_vs_time.txt"
cargo run --release --example plates > "$out/plates.txt"
cargo run --release --example roof > "$out/roof.txt"
cargo run --release --example balloon > "$out/balloon.txt"
cargo run --release --example heavy_cantilever > "$out/heavy_cantilever.txt"
cargo run --release --example sze_cantilevers > "$out/sze_cantilevers.txt"
m=examples/materials/cotton.toml
for angle in 90 45; do
  target/release/ks-fit converge tensile --material $m --angle $angle --width 50 --length 75 \
    --elongation 3.75 --tol 1e-3 --csv "$out/tensile_$angle.csv" --plot "$out/tensile_$angle.svg" \
    > "$out/tensile_$angle.txt"
done
target/release/ks-fit converge bend --material $m --angle 90 --overhang 60 --levels 4 --tol 1e-3 \
  --csv "$out/bend_90.csv" --plot "$out/bend_90.svg" > "$out/bend_90.txt"
echo "wrote $out"
