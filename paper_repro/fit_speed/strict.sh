#!/usr/bin/env bash
# The bundled fabrics fitted with --test-meshes own and with the default --test-meshes strict
# (a fitted curve that the mesh check moves by 0.3 % has its strip refined too), one after the
# other on the same machine; writes strict.md: wall time, Newton
# iterations, the mesh check's parameter and curve changes, G12, and the strips each refined.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --bin ks-fit
out=paper_repro/fit_speed
bin=target/release/ks-fit
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
key() { awk -v k="$2" '$1 == k { print $3; exit }' "$1"; }
g12() { awk '$1 == "g12_pa" && $3 != "{" { print $3; exit }' "$1"; }
{
  echo "# \`--test-meshes strict\` (the default) against \`own\` on the bundled fabrics"
  echo
  echo "Machine: $(nproc) cores. Command: \`bash paper_repro/fit_speed/strict.sh\`. Each fabric fitted"
  echo "with \`--test-meshes own\`, then with \`strict\` (the default). mesh_change: the mesh check's"
  echo "largest change of a determined parameter (of which), curves: its largest change of a"
  echo "fitted curve after the refit (warned at 0.3 %); G12 change: strict's G12 against own's."
  echo
  echo "| fabric | test meshes | wall s | Newton its | mesh_change (of) | curves | G12 change | strips refined |"
  echo "|---|---|---|---|---|---|---|---|"
} > $tmp/md
for f in ${ONLY:-canvas cotton silk denim wool}; do
  for mode in own strict; do
    $bin fit paper_repro/fabrics/$f/fabric.toml -o $tmp/$f-$mode.toml --test-meshes $mode \
      > /dev/null 2> $tmp/$f-$mode.log || [ $? -eq 3 ]
    t=$tmp/$f-$mode.toml
    refined=$(grep -o "per-test mesh: the [0-9.]*° strip refined" $tmp/$f-$mode.log \
      | sed 's/per-test mesh: the //; s/ strip refined//' | paste -sd, - || true)
    change=$(awk -v a="$(g12 $tmp/$f-own.toml)" -v b="$(g12 $t)" 'BEGIN { printf "%+.2f %%", 100 * (b / a - 1) }')
    printf "| %s | %s | %s | %s | %.2f %% (%s) | %.2f %% | %s | %s |\n" "$f" "$mode" \
      "$(key $t wall_seconds)" "$(key $t newton_iterations)" \
      "$(awk -v v="$(key $t mesh_change)" 'BEGIN { print 100 * v }')" \
      "$(key $t mesh_change_parameter | tr -d '"')" \
      "$(awk -v v="$(key $t mesh_change_curves)" 'BEGIN { print 100 * v }')" \
      "$change" "${refined:-none}" >> $tmp/md
  done
done
cp $tmp/md $out/strict.md
cat $out/strict.md
