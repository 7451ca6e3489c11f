#!/usr/bin/env bash
# Fits the five bundled synthetic fabrics (paper_repro/fabrics) with the default settings and
# writes, per fabric, the fitted material with its [fit] table, the report (CSV + SVG) and the
# printed table, then summary.md: wall time, objective evaluations, Newton iterations, the
# share of time per stage and the fit errors. Then methods.md: the hybrid minimiser, BFGS and
# Gauss-Newton on the cotton dataset at degree 2 and 3 (first mesh level only).
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --bin ks-fit
out=paper_repro/fit_speed
bin=target/release/ks-fit
nproc_line="$(nproc) cores"
{
  echo "# ks-fit fit on the bundled synthetic fabrics"
  echo
  echo "Machine: $nproc_line. Command: \`bash paper_repro/fit_speed/run.sh\`."
  echo
  echo "| fabric | wall s | evaluations | Newton its | meshes | degrees w/f/s | warp | weft | bias | drape warp | drape weft | stages (s) |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
} > $out/summary.md
for f in canvas cotton silk denim wool; do
  $bin fit paper_repro/fabrics/$f/fabric.toml -o $out/$f-fit.toml --report $out/$f \
    > $out/$f.txt 2> $out/$f.log
  toml=$out/$f-fit.toml
  get() { grep -m1 "^$1 = " "$toml" | sed "s/^$1 = //"; }
  err() { grep -A4 "angle_deg = $1\$" "$toml" | grep -m1 avg_rel_error | awk '{printf "%.2f %%", 100*$3}'; }
  drape() { awk -v a="$1" '/kind = "bend"/{b=1} b&&/angle_deg/{ok=($3==a)} b&&ok&&/drape_angle_deg/{print $3; exit}' "$toml"; }
  stages=$(sed -n '/^\[fit.stage_seconds\]/,/^$/p' "$toml" | grep ' = ' | sed 's/"//g; s/ = /: /' | paste -sd, -)
  degrees=$(get degrees | sed 's/[{} ]//g; s/warp=//; s/weft=//; s/shear=//; s/,/\//g')
  echo "| $f | $(get wall_seconds) | $(get objective_evaluations) | $(get newton_iterations) | $(get meshes | tr -d '"[]') | $degrees | $(err 90.0) | $(err 0.0) | $(err 45.0) | $(drape 90.0) | $(drape 0.0) | $stages |" >> $out/summary.md
done
{
  echo
  echo "Average relative errors are the paper's Table 3 definition (mean |relative error| over"
  echo "the fitted points of the fitted repeat); drape angles are Table 4's (target 41.5°)."
} >> $out/summary.md

{
  echo "# Minimisers on the cotton dataset (first mesh level, 8x12)"
  echo
  echo "| method | degree | wall s | evaluations | warp | weft | bias | stage stops |"
  echo "|---|---|---|---|---|---|---|---|"
} > $out/methods.md
for d in 2 3; do
  for m in hybrid bfgs gauss-newton; do
    toml=$out/methods-$m-$d.toml
    $bin fit paper_repro/fabrics/cotton/fabric.toml -o $toml --degree $d --method $m \
      --mesh-ladder 8x12 > $out/methods-$m-$d.txt 2> $out/methods-$m-$d.log || true
    if [ -f "$toml" ]; then
      get() { grep -m1 "^$1 = " "$toml" | sed "s/^$1 = //"; }
      err() { grep -A4 "angle_deg = $1\$" "$toml" | grep -m1 avg_rel_error | awk '{printf "%.2f %%", 100*$3}'; }
      stops=$(grep -o 'stage, degree [0-9], mesh [0-9x×]*: rms relative error [0-9.]* % after [0-9]* iterations, [0-9]* evaluations, [0-9]* Newton iterations ([^)]*)' $out/methods-$m-$d.log | sed 's/.*after \([0-9]*\) iterations.*(\(.*\))/\1 its: \2/' | paste -sd';' -)
      echo "| $m | $d | $(get wall_seconds) | $(get objective_evaluations) | $(err 90.0) | $(err 0.0) | $(err 45.0) | $stops |" >> $out/methods.md
    else
      echo "| $m | $d | failed: $(tail -1 $out/methods-$m-$d.log) | | | | | |" >> $out/methods.md
    fi
    rm -f "$toml"
  done
done
echo "wrote $out/summary.md and $out/methods.md"
