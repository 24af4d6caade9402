#!/usr/bin/env bash
# Demo of the flagship scene: grains and water coupled both ways with the default model.
# Run from the repository top:  tools/demo.sh [--out starter-demo.png] [--quick] [--exe EXE --work DIR]
# Builds (incrementally), runs the starter scene inputs/starter/in.pour_and_collapse (800 glass
# beads poured by LIGGGHTS, a 0.03 x 0.02 x 0.06 m water column released onto them, coupled both
# ways, the fix's defaults and `every auto`) in inputs/starter/out-demo/ with HDF5 output
# every 0.01 s, writes the picture (a cut through the middle of the box at four times: the column at
# rest behind the gate, two moments of the collapse, the end; water points coloured by |v|, beads
# to scale) and checks the run against bounds from its inputs. ~10 s after the build on one core
# (--quick: the input's reduced scene, a few seconds). Installs the Debian packages that are
# missing (tools/install_deps.sh); python packages come from tools/python (its own venv).
# --exe: run that liggghts_mpm, without installing or building; --work: the run folder.
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out="$top/starter-demo.png"
quick=0
exe=""
work="$top/inputs/starter/out-demo"
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=$(realpath -m "$2"); shift 2 ;;
    --quick) quick=1; shift ;;
    --exe) exe=$(realpath -m "$2"); shift 2 ;;
    --work) work=$(realpath -m "$2"); shift 2 ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "demo.sh: unknown option $1 (use --out FILE, --quick, --exe EXE, --work DIR)" >&2; exit 2 ;;
  esac
done

if [ -z "$exe" ]; then
  bash "$top/tools/install_deps.sh"
  exe="$top/build/liggghts_mpm"
  echo "== building (incremental)"
  bash "$top/tools/build.sh" >/dev/null
elif [ ! -x "$exe" ]; then
  echo "demo.sh: --exe $exe is not an executable file" >&2; exit 2
fi

input="$top/inputs/starter/in.pour_and_collapse"
mkdir -p "$work"
rm -f "$work"/water_*.h5 "$work"/water.xmf "$work"/beads_*.dump "$work"/log.liggghts "$work"/screen.txt
cp "$input" "$work/in.pour_and_collapse"

# A value of the input: with --quick the one of its 'quick 1' block, else the default line.
val() {
  local v=""
  [ "$quick" = 1 ] && v=$(sed -n "s/^[[:space:]]*\"variable[[:space:]]\+$1[[:space:]]\+index[[:space:]]\+\([^[:space:]\"]\+\).*/\1/p" "$input")
  [ -n "$v" ] || v=$(sed -n "s/^variable[[:space:]]\+$1[[:space:]]\+index[[:space:]]\+\([^[:space:]]\+\).*/\1/p" "$input")
  echo "$v"
}
tpour=$(val tpour); tsettle=$(val tsettle); tflow=$(val tflow)
tout=0.01   # output interval: frames close to the release and to the end of the run (default 0.05 s)

size="default size: $(val nbeads) beads, cell $(val cell) m, $(val ppc)^3 points per cell"
[ "$quick" = 1 ] && size="quick scene: $(val nbeads) beads, cell $(val cell) m, $(val ppc)^3 points per cell"
echo "== starter scene ($size) in ${work#$top/}"
t0=$(date +%s.%N)
# the screen to a file: its last lines are shown if the run fails
(cd "$work" && "$exe" -in in.pour_and_collapse -echo none -var quick "$quick" -var tout "$tout" \
   > screen.txt 2>&1) || {
  echo "demo.sh: the run failed; see ${work#$top/}/log.liggghts:" >&2
  grep -m1 ERROR "$work/log.liggghts" "$work/screen.txt" >&2 || tail -5 "$work/screen.txt" >&2
  exit 1
}
t1=$(date +%s.%N)
awk -v a="$t0" -v b="$t1" 'BEGIN { printf "   run wall time %.1f s\n", b - a }'

# Checks from the inputs alone, on the thermo lines of log.liggghts (the water behind the gate and
# the release: the blocks whose header has f_fluid[1]):
#  - the fluid mass f_fluid[1] is the same in every line (exactly), at most rho0 x the column volume
#    (beads lying in the column when the water is created take their volume from it);
#  - the largest point pressure f_fluid[10] below 5 (rho g h + rho U^2), U = sqrt(2 g h) the speed
#    of a free fall from the column's height h;
#  - the water front f_fluid[4] moves from the gate towards the far wall after the release.
echo "== checks (thermo lines of ${work#$top/}/log.liggghts)"
awk -v rho="$(val rho)" -v g="$(val g)" -v h="$(val hwater)" -v xg="$(val xgate)" -v w="$(val W)" \
    -v L="$(val L)" '
  $1 == "Step" { blk = 0; for (i = 1; i <= NF; i++) { if ($i == "fluid[1]") im = i; if ($i == "fluid[4]") ix = i;
                   if ($i == "fluid[10") ip = i }
                 if (im && ix && ip) { blk = 1; nb++ } next }
  blk && $1 ~ /^[0-9]+$/ && NF >= ip {
    n++; if (n == 1) m0 = $im; if ($im != m0) same = 1; if ($ip > pmax) pmax = $ip
    if (nb == 2) { if (f0 == "") f0 = $ix; f1 = $ix } }
  $1 == "Loop" { blk = 0 }
  END {
    if (n == 0) { print "demo.sh: no thermo line of fix mpm/fluid in the log"; exit 1 }
    mcol = rho * xg * w * h; bound = 5 * (rho * g * h + rho * 2 * g * h); bad = 0
    printf "   fluid mass %s kg in all %d lines: %s (rho0 x column volume %.6g kg, ratio %.4f)\n",
           m0, n, same ? "CHANGES" : "constant", mcol, m0 / mcol
    if (same || m0 > mcol * (1 + 1e-12) || m0 <= 0) bad = 1
    printf "   largest point pressure %.4g Pa = %.3f of rho g h + rho U^2 = %.4g Pa (U = sqrt(2 g h)); bound: 5 times\n",
           pmax, 5 * pmax / bound, bound / 5
    if (!(pmax > 0 && pmax < bound)) bad = 1
    printf "   water front x = %.4f m at the release -> %.4f m at the end (gate %s m, far wall %s m)\n",
           f0, f1, xg, L
    if (!(f1 > f0 && f1 <= L)) bad = 1
    if (bad) { print "demo.sh: a check failed" > "/dev/stderr"; exit 1 }
  }' "$work/log.liggghts"

# Four frames: the column at rest behind the gate, a fifth and a half of the flow time after the
# release, the last frame written. The default size is drawn as a cut one cell wide through the
# middle of the box (y), so that the beads in front do not hide the water (the quick scene, one
# point per cell, whole).
set -- $(awk -v tp="$tpour" -v ts="$tsettle" -v tf="$tflow" -v w="$(val W)" -v c="$(val cell)" 'BEGIN {
  r = tp + ts; printf "%g %g %g %g %g %g %g", tp + ts / 2, r + 0.2 * tf, r + 0.5 * tf, r + tf, r,
  w / 2 - c / 2, w / 2 + c / 2 }')
slab=(--slab "$6" "$7")
[ "$quick" = 1 ] && slab=()
"$top/tools/python" "$top/tools/render_run.py" "$work" --field v --times "$1" "$2" "$3" "$4" \
  --labels "at rest behind the gate" "collapsing" "into the bed" "last frame" "${slab[@]}" --out "$out" \
  --title "Water column released onto poured glass beads (inputs/starter), fix mpm/fluid defaults (pressure projection, two-way coupling) and every auto; gate opens at t = $5 s"
echo "== picture: $out"
