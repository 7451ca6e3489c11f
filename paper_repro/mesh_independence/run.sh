#!/usr/bin/env bash
# Is the fitted material a property of the fabric, not of the mesh? Noise-free data made from
# the bundled cotton material on graded 32x48 strips (twice as fine each way as the fit's last
# level), fitted with the default settings (graded 8x12 -> 16x24 ladder, --test-meshes strict)
# and, for comparison, with --test-meshes own on graded and on uniform cages; prints each fit's G12, a11,
# a22 against the true values and what its mesh check predicts for refining once more. Writes results.md here (about 6 minutes on 2 cores).
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --bin ks-fit
out=paper_repro/mesh_independence
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
bin=target/release/ks-fit
true_material=paper_repro/fabrics/materials/cotton.toml
$bin synth --material $true_material --out "$tmp/data" --max-strain 0.08 --mesh 32x48 \
  --grading 0.8,0.8 2> "$tmp/synth.log"
$bin fit "$tmp/data/fabric.toml" -o "$tmp/graded.toml" --quiet > /dev/null || [ $? -eq 3 ]
$bin fit "$tmp/data/fabric.toml" -o "$tmp/graded-own.toml" --test-meshes own --quiet \
  > /dev/null || [ $? -eq 3 ]
$bin fit "$tmp/data/fabric.toml" -o "$tmp/uniform-own.toml" --grading 0 --test-meshes own --quiet \
  > /dev/null || [ $? -eq 3 ]
value() { awk -v k="$2" '$1 == k && $2 == "=" { print $3; exit }' "$1"; }
check() { awk -v k="$2" '/^\[fit.mesh_check\]/ { t = 1; next } /^\[/ { t = 0 } t && $1 == k { print $3; exit }' "$1"; }
{
  echo "# Mesh independence of the fit (noise-free cotton, data on graded 32x48)"
  echo
  echo "Command: \`bash paper_repro/mesh_independence/run.sh\`. Relative difference of each fitted"
  echo "stiffness from the material that made the data, and the mesh check's predicted change"
  echo "for refining the fit's last level once more (a good check predicts minus the error)."
  echo
  echo "| cages | meshes | wall s | quantity | fitted vs true | mesh check predicts | mesh_change | curves |"
  echo "|---|---|---|---|---|---|---|---|"
  for cage in graded graded-own uniform-own; do
    f="$tmp/$cage.toml"
    meshes=$(awk '$1 == "meshes" { $1 = ""; $2 = ""; print; exit }' "$f")
    for k in a11_pa a22_pa g12_pa; do
      fitted=$(value "$f" $k); truth=$(value $true_material $k)
      awk -v c="$cage" -v m="$meshes" -v w="$(value "$f" wall_seconds)" -v k="$k" -v a="$fitted" \
        -v b="$truth" -v p="$(check "$f" $k)" -v mc="$(value "$f" mesh_change)" \
        -v cc="$(value "$f" mesh_change_curves)" \
        'BEGIN { printf "| %s | %s | %.1f | %s | %+.2f %% | %+.2f %% | %.2f %% | %.2f %% |\n", c, m, w, k, 100 * (a / b - 1), 100 * p, 100 * mc, 100 * cc }'
    done
  done
} > $out/results.md
cat $out/results.md
