#!/usr/bin/env bash
# The paper's three showcase scenes (Clyde et al. 2017 Figures 1 and 5) on the five bundled
# fabrics as fitted by `ks-fit fit` (paper_repro/fit_speed/<fabric>-fit.toml), each on the mesh
# the automatic choice keeps (--tol 1 %: three meshes, Richardson). Writes each scene's folder
# (shape.obj, shape.ply, CSV, scene.toml, scene.png) under out/, the table results.md and one
# figure per scene with the five fabrics side by side at one scale (drape.png, picture-frame.png,
# corner-pull.png; GPU renders, a software driver will do).
# KS_FIT=path uses that binary instead of building one; `run.sh --figures` only redraws the figures
# from the shapes already in out/.
set -euo pipefail
cd "$(dirname "$0")/../.."
if [ -z "${KS_FIT:-}" ]; then
  cargo build --release --bin ks-fit
  KS_FIT=target/release/ks-fit
fi
here=paper_repro/scenes
mkdir -p "$here/out"
if [ "${1:-}" != --figures ]; then
table="$here/results.md"
{
  echo "# Showcase scenes on the bundled fits"
  echo
  echo "Made by \`bash paper_repro/scenes/run.sh\` on $(nproc) cores. Mesh: the automatic choice"
  echo "(coarsest of three meshes whose Richardson estimate is below 1 %), or the finest with a"
  echo "warning when none is; time: the whole ladder."
  echo
  echo "Figures (GPU renders of each scene's shape.obj, the five fabrics left to right: canvas,"
  echo "cotton, silk, denim, wool; one camera and scale per figure): drape.png (the layout of"
  echo "Figure 1), picture-frame.png and corner-pull.png (Figure 5). Red lines run along the warp,"
  echo "blue along the weft, every 5 cm of fabric in the drape and 5 mm in the 10 cm squares."
  echo
  echo "| fabric | scene | QoI | value | mesh | est. error | ladder values | stable | iterations | time (s) |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
} > "$table"
for fabric in canvas cotton silk denim wool; do
  mat=paper_repro/fit_speed/$fabric-fit.toml
  for scene in drape picture-frame corner-pull; do
    out=$here/out/$fabric-$scene
    start=$(date +%s.%N)
    if ! "$KS_FIT" --force scene $scene --material "$mat" --out "$out" -v > /dev/null 2> "$out.log"; then
      echo "| $fabric | $scene | failed: $(tail -1 "$out.log") | | | | | | | |" >> "$table"
      continue
    fi
    secs=$(echo "$(date +%s.%N) - $start" | bc)
    get() { grep -m1 "^$1 = " "$out/scene.toml" | sed "s/^$1 = //; s/\"//g" || true; }
    ladder=$(awk '/^\[\[ladder\]\]/{l=1} l && /^qoi = /{printf "%s%.4g", s, $3; s=", "}' "$out/scene.toml")
    est=$(get estimated_error); est=${est:-none}
    printf "| %s | %s | %s | %.4g | %s | %s | %s | %s | %s | %.1f |\n" "$fabric" "$scene" \
      "$(get qoi)" "$(get qoi_value)" "$(get mesh)" "$est" "$ladder" "$(get stable)" \
      "$(get iterations)" "$secs" >> "$table"
  done
done
cat "$table"
fi
# the figures: Clyde et al. 2017 Figure 1 (drapes) and Figure 5 (frame, corner pull) layouts
for scene in drape picture-frame corner-pull; do
  # the flat squares from above without a ground (the corner pulls buckle tall enough that the
  # automatic choice would take them for hanging shapes)
  look=(--image 480x400 --view above --ground off)
  [ "$scene" = drape ] && look=(--image 480x600)
  shapes=()
  for fabric in canvas cotton silk denim wool; do shapes+=("$here/out/$fabric-$scene/shape.obj"); done
  "$KS_FIT" --force render "${shapes[@]}" --out "$here/$scene.png" "${look[@]}"
done
