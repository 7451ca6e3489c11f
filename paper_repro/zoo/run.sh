#!/bin/bash
# The fabric zoo: writes a seeded zoo of plausible fabrics, fits it with `ks-fit batch`
# (resumable: rerun to go on where a run stopped) and summarises the fits against the truth.
#
#   bash paper_repro/zoo/run.sh [DRAWS] [WORK_DIR]
#
# DRAWS (default 40) draws give DRAWS/2 law fabrics and DRAWS/2 analytic ones. Two zoos are
# written: `clean` (the law fabrics without the lab's artefacts: does the fit recover the
# truth?) and `lab` (every fabric as a lab would measure it: does the fit survive?).
set -euo pipefail
cd "$(dirname "$0")/../.."
DRAWS=${1:-40}
WORK=${2:-target/zoo}
SEED=58
cargo build --release --bin ks-fit --example zoo
for kind in clean lab; do
  dir=$WORK/$kind
  flag=()
  if [ "$kind" = clean ]; then flag=(--clean); fi
  target/release/examples/zoo generate "$dir" --count "$DRAWS" --seed "$SEED" --models-every 20 "${flag[@]}"
  # a fit that ends FIT FAILED exits 3 and the batch goes on; the summary counts it
  target/release/ks-fit batch "$dir/manifest.csv" --out "$dir/fits" || true
  target/release/examples/zoo summary "$dir" > "paper_repro/zoo/summary-$kind.md"
done
