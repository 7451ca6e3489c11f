#!/usr/bin/env bash
# Regenerates the bundled SYNTHETIC fabric datasets from the reference materials in
# materials/ with the virtual lab: three repeats per tensile angle with paper-like
# repeat-to-repeat scatter (one random force scale of 15 % and 1° of misalignment per repeat,
# 1.5 % point noise) up to 8 % strain, and the two cantilever overhangs at 41.5°. The datasets then give the
# measured thickness of Clyde et al. 2017, Table 2, as the fit's starting point (the
# materials hold the effective bending thickness the fit should find). The strips are solved on
# graded 32x48 cages, twice as fine each way as the fit's last level (16x24), so the fit meets
# data its own mesh did not make.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --bin ks-fit
# name:measured thickness (mm):seed; ONLY="cotton silk" remakes a subset
for m in canvas:0.53:1 cotton:0.18:2 silk:0.18:3 denim:0.66:4 wool:1.28:5; do
  IFS=: read -r name measured seed <<< "$m"
  if [ -n "${ONLY:-}" ] && [[ " $ONLY " != *" $name "* ]]; then continue; fi
  out=paper_repro/fabrics/$name
  rm -rf "$out"
  target/release/ks-fit synth --material paper_repro/fabrics/materials/$name.toml --out "$out" \
    --repeats 3 --noise 0.15 --misalign 1 --max-strain 0.08 --seed $seed --mesh 32x48 --grading 0.8,0.8
  sed -i "s/^thickness_mm = .*/thickness_mm = $measured    # measured (Clyde et al. 2017, Table 2)/" "$out/fabric.toml"
done
