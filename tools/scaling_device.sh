#!/usr/bin/env bash
# Strong scaling of liggghts_mpm on a bare many-core machine, from a bundle of the build with its
# runtime (shared libraries, Open MPI's orterun and plugins; see docs/scaling.md "Harness").
# Usage: bash tools/scaling_device.sh BUNDLE.tar.xz INPUT N "P1 P2 ..." STEPS_EOS STEPS_PROJ BALANCE [CEILING_N]
# Writes $OUT/scaling.txt (default /tmp/out), the RESULTS format of tools/scaling.py: per run
#   MODEL np P rc RC loop T RESULT ...       (the input's RESULT line)
#   MODEL np P STAT fix mpm/fluid: ...       (fix mpm/fluid's end-of-run lines of the timed run)
# then `tools/python tools/scaling.py report scaling.txt` tabulates them. CEILING_N > 0 adds the
# machine's own ceiling: for each P, P independent one-rank eos runs at n CEILING_N, one per core,
# against one alone (lines `ceiling P K loop T` for each run k).
set -u
tarball=$1; IN=$(realpath "$2"); N=${3:-50}; PS=${4:-"1 2 4 8 16"}; SE=${5:-50}; SP=${6:-30}; BAL=${7:-1}; CN=${8:-0}
O=${OUT:-/tmp/out}; mkdir -p $O
# the bundle is unpacked into $BUNDLE_DIR (default /opt) once
BD=${BUNDLE_DIR:-/opt}; mkdir -p "$BD"
[ -d "$BD/bundle" ] || tar -xJf "$tarball" -C "$BD" || exit 1
B=$BD/bundle
export LD_LIBRARY_PATH=$B/lib OPAL_PREFIX=$B/ompi OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl=self,vader OMPI_MCA_pml=ob1 OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mtl=^ofi OMPI_MCA_osc=^ucx,pt2pt
run() { # model ranks steps
  local d=/tmp/w-$1-$2; mkdir -p $d; cd $d
  timeout 300 $B/bin/orterun --bind-to core -np $2 $B/bin/liggghts_mpm -in $IN -var n $N -var pressure $1 \
    -var nsteps $3 -var balance $BAL -echo none -log log.txt > screen.txt 2>&1
  local rc=$?
  echo "$1 np $2 rc $rc loop $(grep 'Loop time' screen.txt | tail -1 | awk '{print $4}') $(grep RESULT screen.txt | tail -1)" | tee -a $O/scaling.txt
  for k in "wall time in this run" "halo exchanges in this run" "work per rank"; do
    grep "^fix mpm/fluid: $k" screen.txt | tail -1 | sed "s/^/$1 np $2 STAT /" >> $O/scaling.txt
  done
  cd - >/dev/null
}
for p in $PS; do run eos $p $SE; done
for p in $PS; do run projection $p $SP; done
if [ "$CN" -gt 0 ]; then
  for p in $PS; do
    for k in $(seq 0 $((p - 1))); do
      d=/tmp/c-$p-$k; mkdir -p $d
      (cd $d && $B/bin/orterun -np 1 --bind-to none taskset -c $k $B/bin/liggghts_mpm -in $IN -var n $CN -var nsteps $SE -echo none -log none > screen.txt 2>&1) &
    done
    wait
    for k in $(seq 0 $((p - 1))); do
      echo "ceiling $p $k loop $(grep 'Loop time' /tmp/c-$p-$k/screen.txt | tail -1 | awk '{print $4}')" | tee -a $O/scaling.txt
    done
  done
fi
