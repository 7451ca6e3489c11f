#!/usr/bin/env bash
# Speed against accuracy of FITTED triangle models: the example cotton's synthetic lab data
# (made by the shell), each triangle model fitted to it by `ks-fit fit --model`, then the same
# tests and scenes as paper_repro/models charted against the converged shell.
# Run from anywhere: bash paper_repro/models/fitted/run.sh  (WORK= sets the scratch folder)
set -euo pipefail
cd "$(dirname "$0")/../../.."
cargo build --release --quiet
W="${WORK:-target/model-fits}"
B=target/release/ks-fit
mkdir -p "$W"
# the strips on graded 64x96 cages, near their converged forces (within 0.2 % of 128x192 on an
# off-axis strip, paper_repro/off_axis), so that every model is fitted to the material's
# strips rather than to one discretisation of them
$B synth --material examples/materials/cotton.toml --out "$W/data" --points 10 --max-strain 0.05 --force \
    --mesh 64x96 --grading 0.8,0.8
fits=()
for m in soft-constraints stvk-ds xpbd springs; do
    s=$(date +%s)
    $B fit "$W/data/fabric.toml" --model "$m" -o "$W/$m.toml" --force > "$W/$m.log" 2>&1 || echo "fit $m: exit $? (see $W/$m.log)"
    echo "fit $m: $(( $(date +%s) - s )) s; $(grep '^fitted' "$W/$m.log" || true)"
    fits+=("$W/$m.toml")
done
cargo run --release --quiet --example model_chart -- --fits "${fits[@]}"
