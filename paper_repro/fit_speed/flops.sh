#!/usr/bin/env bash
# The assembly's flops against this machine's peak: runs the shell bench (benches/shell.rs),
# which counts the flops of the face loop's stencil loops, measures one core's AVX2 FMA peak,
# the extra cost of the paper's law over the linear one and a Newton solve's split, and writes
# its lines into flops.md. Run it on a quiet machine.
#
#   bash paper_repro/fit_speed/flops.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
out=paper_repro/fit_speed/flops.md
lines=$(cargo bench --quiet --bench shell 2>/dev/null)
{
  echo "# The assembly's flops against the peak"
  echo
  echo "Made by \`bash paper_repro/fit_speed/flops.sh\` (\`cargo bench --bench shell\`: medians of"
  echo "repeated runs, $(nproc) cores). A 32 × 48 bias strip under a smooth deformation; the flops"
  echo "are those of the face loop's stencil loops (\`src/assembly/face_loop.rs\`: the surface"
  echo "derivatives and the gradient, 15 multiply-adds per stencil point each; R_a = Σ_k W_ak H_k·,"
  echo "225 per point; the packed face blocks H_ab, 45 multiply-adds and 9 adds per pair a ≤ b),"
  echo "counted from each Gauss point's stencil size; the kinematics and the law at the point take"
  echo "time and are not counted. The peak is one core's 4-wide fused multiply-adds in twelve"
  echo "independent chains, measured."
  echo
  echo '```'
  echo "$lines"
  echo '```'
} > "$out"
echo "wrote $out"
