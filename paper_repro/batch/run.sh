#!/usr/bin/env bash
# Throughput of `ks-fit batch` on the five bundled synthetic fabrics (paper_repro/fabrics), with
# 1 and with 2 fits side by side on this machine, default fit options; writes results.md here.
# The batch outputs go to a temporary folder (OUT=... to keep them). Also checks that the two
# runs wrote the same materials (timing lines aside).
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --bin ks-fit
here=paper_repro/batch
out="${OUT:-$(mktemp -d)}"
manifest="$out/library.csv"
{
  echo "fabric,dataset"
  for f in canvas cotton denim silk wool; do
    echo "$f,$PWD/paper_repro/fabrics/$f/fabric.toml"
  done
} > "$manifest"
declare -A secs
for jobs in 1 2; do
  rm -rf "$out/jobs$jobs"
  start=$(date +%s.%N)
  target/release/ks-fit batch "$manifest" --out "$out/jobs$jobs" --jobs "$jobs" 2> "$out/jobs$jobs.log" || true
  end=$(date +%s.%N)
  secs[$jobs]=$(awk -v a="$start" -v b="$end" 'BEGIN { print b - a }')
done
same=yes
for f in canvas cotton denim silk wool; do
  a=$(grep -v seconds "$out/jobs1/$f/material.toml" | grep -v '^"')
  b=$(grep -v seconds "$out/jobs2/$f/material.toml" | grep -v '^"')
  [ "$a" == "$b" ] || same="no ($f differs)"
done
{
  echo "# ks-fit batch: throughput on the bundled fabrics"
  echo
  echo "Made by \`bash paper_repro/batch/run.sh\` on $(nproc) cores ($(date -u +%F)): the five"
  echo "bundled synthetic fabrics (paper_repro/fabrics) with the default fit options, each fit"
  echo "with its report page."
  echo
  echo "| jobs | wall s | fabrics per hour | per fabric (s, from its status.toml) |"
  echo "|---|---|---|---|"
  for jobs in 1 2; do
    per=$(awk -F' = ' '/^seconds/ {printf "%s%.1f", sep, $2; sep=", "}' "$out"/jobs$jobs/{canvas,cotton,denim,silk,wool}/status.toml)
    printf "| %s | %.1f | %.0f | %s |\n" "$jobs" "${secs[$jobs]}" "$(awk -v s="${secs[$jobs]}" 'BEGIN { print 5 * 3600 / s }')" "$per"
  done
  echo
  echo "Materials identical between the two runs (timing lines aside): $same."
  echo
  echo "Summary of the 2-job run (\`summary.csv\`):"
  echo
  echo '```'
  cat "$out/jobs2/summary.csv"
  echo '```'
} > "$here/results.md"
cat "$here/results.md"
