#!/usr/bin/env bash
# Dam-break demo (square water column, Martin & Moyce 1952) at MPM16.
# Run from the repository top:  tools/demo.sh [--out dambreak-demo.png] [--cells 16]
# Builds (incrementally), runs inputs/dambreak/in.dambreak in
# inputs/dambreak/out-demo/ with HDF5 snapshots (~8 frames, one at gate removal),
# writes the picture (snapshots coloured by |v| + front and wall height against
# the experiment) and prints the RMS errors. Takes ~10 s after the build.
# Installs the Debian packages that are missing (tools/install_deps.sh);
# python packages come from tools/python (its own venv).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out="$top/dambreak-demo.png"
cells=16
tend=3.0
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=$(realpath -m "$2"); shift 2 ;;
    --cells) cells="$2"; shift 2 ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "demo.sh: unknown option $1 (use --out FILE, --cells N)" >&2; exit 2 ;;
  esac
done

bash "$top/tools/install_deps.sh"
exe="$top/build/liggghts_mpm"
echo "== building (incremental)"
bash "$top/tools/build.sh" >/dev/null

input="$top/inputs/dambreak/in.dambreak"
work="$top/inputs/dambreak/out-demo"
mkdir -p "$work"
rm -f "$work"/dambreak_*.h5 "$work"/dambreak.xmf "$work"/front.csv "$work"/log.liggghts
cp "$input" "$work/in.dambreak"

# Time step and settling steps exactly as the input computes them (automatic dt):
# HDF5 every h5every steps with h5every dividing the settling steps, so that one
# frame is the column at gate removal and ~8 frames cover T = 0 ... tend.
val() { sed -n "s/^variable[[:space:]]\+$1[[:space:]]\+index[[:space:]]\+\([^[:space:]]\+\).*/\1/p" "$input"; }
# (the default pressure projection has no sound speed: dt = dtfactor dx / (2 sqrt(g h)))
h5every=$(awk -v a="$(val width)" -v h="$(val height)" -v n="$cells" \
  -v g="$(val g)" -v f="$(val dtfactor)" -v ts="$(val tsettle)" -v tend="$tend" 'BEGIN {
    dx = a / n; dt = f * dx / (2 * sqrt(g * h))
    ns = ts / dt; nsettle = (ns == int(ns)) ? ns : int(ns) + 1
    target = tend * sqrt(a / g) / dt / 8
    m = int(nsettle / target + 0.5); if (m < 1) m = 1
    print int(nsettle / m + 0.5) }')

echo "== dam break MPM$cells (h5every $h5every) in ${work#$top/}"
t0=$(date +%s.%N)
(cd "$work" && "$exe" -in in.dambreak -echo none -screen none \
   -var cells "$cells" -var tend "$tend" -var h5every "$h5every") || {
  echo "demo.sh: the run failed; see ${work#$top/}/log.liggghts:" >&2
  grep -m1 ERROR "$work/log.liggghts" >&2 || tail -5 "$work/log.liggghts" >&2
  exit 1
}
t1=$(date +%s.%N)
awk -v a="$t0" -v b="$t1" 'BEGIN { printf "   run wall time %.1f s\n", b - a }'

"$top/tools/python" "$top/tools/render_dambreak.py" "$work" --times 0 0.5 1 1.5 2 2.5 3 \
  --front "$work/front.csv" --out "$out" \
  --title "Dam break (Martin & Moyce 1952), MPM$cells, points coloured by |v|"
echo "== RMS errors against Martin & Moyce (1952), units of the column width a"
"$top/tools/python" "$top/tools/dambreak_error.py" "$work/front.csv"
echo "== picture: $out"
