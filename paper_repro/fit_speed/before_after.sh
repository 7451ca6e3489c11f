#!/usr/bin/env bash
# Wall and CPU time of `ks-fit fit` on the five bundled fabrics, for the working tree's binary
# and for the binary of an earlier commit, run one after the other on this machine (default
# settings both; the earlier commit's defaults are its own). Usage:
#   bash paper_repro/fit_speed/before_after.sh COMMIT [RUNS]
# Writes paper_repro/fit_speed/before_after.md with the median of RUNS runs (default 1), and
# each binary's count of Newton iterations (the fitted file's newton_iterations: each binary
# counts by its own rules; since 2026-12-04 the attempts a strip gave up on are counted too).
set -euo pipefail
cd "$(dirname "$0")/../.."
base_commit=${1:?usage: before_after.sh COMMIT [RUNS]}
runs=${2:-1}
root=$(pwd)
tmp=$(mktemp -d)
trap 'git worktree remove --force "$tmp/base" >/dev/null 2>&1 || true; rm -rf "$tmp"' EXIT
git worktree add -q "$tmp/base" "$base_commit"
# the earlier commit builds in a target directory of its own (target/before_after, kept for
# the next run): sharing this tree's, cargo found the tree's own build fresh afterwards and
# left the earlier binary in target/release, so that "after" ran the earlier commit
cargo build --release --bin ks-fit -q
cp target/release/ks-fit "$tmp/ks-fit-new"
(cd "$tmp/base" && cargo build --release --bin ks-fit --target-dir "$root/target/before_after" -q)
cp target/before_after/release/ks-fit "$tmp/ks-fit-base"
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
{
  echo "# ks-fit fit: before ($base_commit) and after (working tree)"
  echo
  echo "Machine: $(nproc) cores. Command: \`bash paper_repro/fit_speed/before_after.sh $base_commit $runs\`;"
  echo "median of $runs run(s) per binary; wall and CPU (user + system) seconds."
  echo
  echo "| fabric | before wall s | before CPU s | before Newton its | after wall s | after CPU s | after Newton its |"
  echo "|---|---|---|---|---|---|---|"
} > "$tmp/table.md"
for f in canvas cotton silk denim wool; do
  row="| $f"
  for which in base new; do
    walls=(); cpus=()
    for _ in $(seq "$runs"); do
      /usr/bin/time -f "%e %U %S" -o "$tmp/t" "$tmp/ks-fit-$which" fit \
        paper_repro/fabrics/$f/fabric.toml -o "$tmp/$f-$which.toml" --quiet > /dev/null 2>&1 \
        || [ $? -eq 3 ]  # 3: the fit ran but missed --max-error (its verdict), still timed
      # GNU time puts "Command exited with non-zero status N" before the times
      read -r wall user sys < <(tail -n 1 "$tmp/t")
      walls+=("$wall"); cpus+=("$(awk -v u="$user" -v s="$sys" 'BEGIN {print u + s}')")
    done
    its=$(awk '$1 == "newton_iterations" { print $3; exit }' "$tmp/$f-$which.toml")
    row="$row | $(printf '%s\n' "${walls[@]}" | median) | $(printf '%s\n' "${cpus[@]}" | median) | $its"
  done
  echo "$row |" >> "$tmp/table.md"
done
cp "$tmp/table.md" paper_repro/fit_speed/before_after.md
cat paper_repro/fit_speed/before_after.md
