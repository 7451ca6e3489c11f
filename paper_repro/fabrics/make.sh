#!/usr/bin/env bash
# Regenerates the bundled SYNTHETIC fabric datasets from the reference materials in
# materials/ with the virtual lab: three repeats per tensile angle with paper-like
# repeat-to-repeat scatter (one random force scale of 15 % and 1° of misalignment per repeat,
# 1.5 % point noise) up to 8 % strain, and the two cantilever overhangs at 41.5°. The datasets then give the
# measured thickness of Clyde et al. 2017, Table 2, as the fit's starting point (the
# materials hold the effective bending thickness the fit should find).
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --bin ks-fit
seed=1
for m in canvas:0.53 cotton:0.18 silk:0.18 denim:0.66 wool:1.28; do
  name=${m%%:*}; measured=${m##*:}
  out=paper_repro/fabrics/$name
  rm -rf "$out"
  target/release/ks-fit synth --material paper_repro/fabrics/materials/$name.toml --out "$out" \
    --repeats 3 --noise 0.15 --misalign 1 --max-strain 0.08 --seed $seed
  sed -i "s/^thickness_mm = .*/thickness_mm = $measured    # measured (Clyde et al. 2017, Table 2)/" "$out/fabric.toml"
  seed=$((seed + 1))
done
