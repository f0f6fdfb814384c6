#!/usr/bin/env bash
# Renders the pictures of docs/results/ (issue #6 item 5) in the style of the thesis' figures:
#   fig3_10_*  reachable targets after teaching setup I with 1 and 4 areas (Fig. 3.10)
#   fig4_6_*   the implicit scene model S of Eq. 4.1 for the same sessions (Fig. 4.6)
#   fig3_11_*, fig4_7_*  the same for setup II with 21 areas (Fig. 3.11 right, Fig. 4.7 right)
#   fig6_5_*   confidence slices C(x) at several heights (Fig. 6.5), with the arm and from above
#   fig7_7_*   the ITM graph of setup I (4 areas) with planned paths (Fig. 7.7)
#   fig8_4_*   the ITM graph of the 9-DoF arm (8 areas) with planned paths (Fig. 8.4)
# Small sessions are taught with the simulated tutor (`teach`), evaluated on a coarse grid
# (`eval reachable`, `eval scene-model`, `plan`) and drawn offscreen (`render`). Deterministic
# (fixed seeds). Takes some minutes on two cores.
#
# Usage: scripts/render_results.sh [BUILD_DIR] [OUT_DIR]
#   BUILD_DIR  a configured and built build directory (default: build); its flexirob-cli is used
#   OUT_DIR    where the PNGs and the JSON they were drawn from go (default: docs/results)
# Environment: SPACING (grid spacing of the evaluations, default 0.1 m), GOALS (planned goals,
# default 12), WIDTH / HEIGHT (default 800 x 600), DATA_DIR (keep the sessions and the
# evaluations' JSON there; default: a temporary directory, removed at the end), REUSE=1 (with
# DATA_DIR: keep the sessions taught before instead of teaching again).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build}"
out="${2:-$root/docs/results}"
cli="$build/app/cli/flexirob-cli"
spacing="${SPACING:-0.1}"
goals="${GOALS:-12}"
width="${WIDTH:-800}"
height="${HEIGHT:-600}"

if [[ ! -x "$cli" ]]; then
  echo "error: $cli not found (build the flexirob-cli target first)" >&2
  exit 2
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
data_dir="${DATA_DIR:-$work/data}"
mkdir -p "$out" "$data_dir"

step() { echo "render_results: $*" >&2; }
render_sized() { local w="$1" h="$2"; shift 2; "$cli" render --width "$w" --height "$h" --supersample 2 --no-scene-areas "$@" >/dev/null; }
render() { render_sized "$width" "$height" "$@"; }

# produce FILE LABEL COMMAND...: runs COMMAND, which writes FILE, unless REUSE=1 and FILE is
# there from an earlier run.
produce() {
  local file="$1" label="$2"
  shift 2
  if [[ -n "${REUSE:-}" && -s "$file" ]]; then
    step "reusing $file"
    return
  fi
  step "$label"
  "$@"
}
# to_file FILE COMMAND...: COMMAND's stdout into FILE, complete or not at all.
to_file() {
  local file="$1"
  shift
  "$@" >"$file.part"
  mv "$file.part" "$file"
}

# --- Sessions -------------------------------------------------------------------------------
# teach NAME ARGS...: $data_dir/NAME.session.json
teach() {
  local name="$1"
  shift
  local file="$data_dir/$name.session.json"
  produce "$file" "teach $name" to_file "$work/teach_$name.json" "$cli" teach "$@" --seed 1 --overwrite --out "$file"
}
teach setup_I_1areas --robot lwr4 --scene setup_I --areas 1
teach setup_I_4areas --robot lwr4 --scene setup_I --areas 4
teach setup_II_21areas --robot lwr4 --scene setup_II --areas 21
teach arm9_8areas --robot arm9 --scene arm9_areas --areas 8

# --- Evaluations ----------------------------------------------------------------------------
# evaluate FILE ARGS...: flexirob-cli ARGS > FILE
evaluate() {
  local file="$1"
  shift
  produce "$file" "$1 $2 -> $(basename "$file")" to_file "$file" "$cli" "$@"
}
for name in setup_I_1areas setup_I_4areas setup_II_21areas; do
  session="$data_dir/$name.session.json"
  evaluate "$data_dir/$name.reachable.json" eval reachable --session "$session" --spacing "$spacing"
  evaluate "$data_dir/$name.scene_model.json" eval scene-model --session "$session" --spacing "$spacing"
done
evaluate "$data_dir/setup_I_4areas.plan.json" plan --session "$data_dir/setup_I_4areas.session.json" --goals "$goals" --seed 1
evaluate "$data_dir/arm9_8areas.plan.json" plan --session "$data_dir/arm9_8areas.session.json" --goals "$goals" --seed 1

# --- Pictures -------------------------------------------------------------------------------
for areas in 1 4; do
  data="$data_dir/setup_I_${areas}areas"
  # Front-right, low: the targets behind the box (left of the robot, +y) and under the board stay
  # visible; the thesis' Fig. 3.10 shows setup I from the front.
  step "fig3_10_setup_I_${areas}areas.png"
  render --session "$data.session.json" --hide ghosts,itm --point-size 5 --reachable "$data.reachable.json" \
    --view front-right --legend --out "$out/fig3_10_setup_I_${areas}areas.png"
  # S without the obstacles (part of it lies inside them), the samples for orientation.
  step "fig4_6_setup_I_${areas}areas.png"
  render --session "$data.session.json" --hide ghosts,itm --point-size 6 --scene-model "$data.scene_model.json" \
    --no-obstacles --view front-right --legend --out "$out/fig4_6_setup_I_${areas}areas.png"
done
# Setup II from the front-right as well: the gaps between the boxes and the robot, and the
# targets beside and behind the right box, stay visible. Wider, so that the legend of 21 areas
# leaves the scene free.
data="$data_dir/setup_II_21areas"
step "fig3_11_setup_II_21areas.png"
render_sized 1100 700 --session "$data.session.json" --hide ghosts,itm --point-size 5 --reachable "$data.reachable.json" \
  --view front-right --legend --out "$out/fig3_11_setup_II_21areas.png"
step "fig4_7_setup_II_21areas.png"
render_sized 1100 700 --session "$data.session.json" --hide ghosts,itm --point-size 6 --scene-model "$data.scene_model.json" \
  --no-obstacles --view front-right --legend --out "$out/fig4_7_setup_II_21areas.png"
step "fig6_5_setup_I_4areas.png"
render --session "$data_dir/setup_I_4areas.session.json" --hide ghosts,itm --point-size 4 \
  --confidence-heights 0.3,0.6 --confidence-resolution 80 --view front-left --legend \
  --out "$out/fig6_5_setup_I_4areas.png"
# As Fig. 6.5: one slice per height, seen from above (front, -x, at the bottom; +y, the robot's
# left, on the left); the robot, the obstacles and the samples left out (the board and the arm
# would hide the slice, samples at other heights would mislead).
for z in 0.1 0.3 0.6 0.9; do
  step "fig6_5_setup_I_4areas_z$z.png"
  render_sized 600 600 --session "$data_dir/setup_I_4areas.session.json" --hide ghosts,itm,samples --no-robot --no-obstacles \
    --confidence-heights "$z" --confidence-resolution 120 --view top --legend \
    --out "$out/fig6_5_setup_I_4areas_z$z.png"
done
step "fig7_7_setup_I_4areas.png"
render --session "$data_dir/setup_I_4areas.session.json" --hide ghosts,samples --plan "$data_dir/setup_I_4areas.plan.json" --plan-paths 5 \
  --view front-left --legend --out "$out/fig7_7_setup_I_4areas.png"
step "fig8_4_arm9_8areas.png"
render --session "$data_dir/arm9_8areas.session.json" --hide ghosts,samples --plan "$data_dir/arm9_8areas.plan.json" --plan-paths 5 \
  --view front-left --legend --out "$out/fig8_4_arm9_8areas.png"

ls -l "$out"/*.png >&2
