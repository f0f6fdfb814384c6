#!/usr/bin/env bash
# Builds a small study: several simulated participants taught with `flexirob-cli teach` in
# setup A (different seeds and deflection-circle diameters), then reviews the folder with the
# study analysis (docs/STUDY.md): tables as CSV and the MDS scatter plot.
#
#   scripts/study_demo.sh [BUILD_DIR] [OUT_DIR]
#
# BUILD_DIR defaults to ./build, OUT_DIR to ./study-demo (replaced).
set -euo pipefail
build=${1:-build}
out=${2:-study-demo}
cli="$build/app/cli/flexirob-cli"
if [[ ! -x "$cli" ]]; then
  echo "error: $cli not found; build the flexirob-cli target first" >&2
  exit 2
fi
rm -rf "$out"
mkdir -p "$out"
participant=0
for seed in 1 2 3 4; do
  for diameter in 0.02 0.08; do
    participant=$((participant + 1))
    name=$(printf 'p%02d' "$participant")
    echo "teach $name: seed $seed, circle diameter $diameter m" >&2
    "$cli" teach --scene setup_A --areas 2 --seed "$seed" --diameter "$diameter" --candidates 8 --overwrite \
      --out "$out/$name.db" > "$out/$name.teach.json"
  done
done
"$cli" review --study "$out" --csv-dir "$out/tables" --plot "$out/mds.png" > "$out/review.json"
echo "review: $out/review.json, tables in $out/tables, plot $out/mds.png" >&2
