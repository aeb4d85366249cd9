#!/bin/sh
# `mpirun -np N trac0r render`: 1, 2 and 3 ranks give the single-process image and passes
# bit for bit; a rank that cannot open its device ends the job with one trac0r message
# and status 2; ranks given different options are refused; a render stopped by SIGTERM
# under MPI resumes, with another number of ranks, to the single-process image (and
# variance: the checkpoint and the tile messages carry its sums of squares); the same
# checkpoint resumes without mpirun, and one written without it resumes under mpirun.
# Usage: mpi_check.sh TRAC0R_BINARY SCRATCH_DIR MPIEXEC ranks|resume (two CTests: each
# mpirun start costs a second or more)
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"
MPIRUN="$3 --oversubscribe"
PART=$4
# The CI runs as root; Open MPI refuses that unless told.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

R="render --width 100 --height 70 --spp 6 --threads 1 --passes all"
if [ "$PART" = ranks ]; then
    "$BIN" $R --out single.pfm 2>err.txt || fail "single-process render: $(cat err.txt)"
    for n in 1 2 3; do
        $MPIRUN -np $n "$BIN" $R --out np$n.pfm 2>err.txt || fail "np $n: exit $?: $(cat err.txt)"
        for f in "" .albedo .normal .depth .id .variance; do
            cmp -s single$f.pfm np$n$f.pfm || fail "np $n: np$n$f.pfm differs from single$f.pfm"
        done
        grep -q "tiles" err.txt || fail "np $n: no progress lines"
    done
    # --verbose: rank 0 reports every rank's time, one line each, and the image is the same.
    $MPIRUN -np 2 "$BIN" $R --verbose --out verbose.pfm 2>err.txt || fail "np 2 --verbose: $(cat err.txt)"
    n=$(grep -c "rank [01]: setup" err.txt)
    [ "$n" -eq 2 ] || fail "np 2 --verbose: $n lines of per-rank times, expected 2: $(cat err.txt)"
    cmp -s single.pfm verbose.pfm || fail "np 2 --verbose: the image differs"

    # The preview stride: tiles are aligned to it.
    "$BIN" $R --stride 3 --out stride.pfm 2>/dev/null
    $MPIRUN -np 2 "$BIN" $R --stride 3 --out stride2.pfm 2>/dev/null
    cmp -s stride.pfm stride2.pfm || fail "np 2 --stride 3 differs from a single process"

    # One rank cannot open its device: one message from trac0r, status 2, no image.
    $MPIRUN -np 1 "$BIN" $R --out bad.pfm : -np 1 "$BIN" $R --out bad.pfm --device opencl:999 \
        >out.txt 2>err.txt
    rc=$?
    [ $rc -eq 2 ] || fail "a failing rank: exit $rc, expected 2: $(cat err.txt)"
    n=$(grep -c "^trac0r render:" err.txt)
    [ "$n" -eq 1 ] || fail "a failing rank: $n trac0r messages, expected 1: $(cat err.txt)"
    grep -q "opencl\|OpenCL\|device" err.txt || fail "a failing rank: the message does not name the device"
    [ -e bad.pfm ] && fail "a failing rank: an image was written"
    $MPIRUN -np 1 "$BIN" $R --out bad.pfm : -np 1 "$BIN" $R --seed 9 --out bad.pfm >out.txt 2>err.txt
    rc=$?
    [ $rc -eq 2 ] || fail "ranks with different seeds: exit $rc, expected 2"
    [ -e bad.pfm ] && fail "ranks with different seeds: an image was written"

fi

# SIGTERM under MPI (to mpirun, or to one worker rank): rank 0 writes the finished tiles
# and the checkpoint; resuming with three ranks finishes the rest.
if [ "$PART" = resume ]; then
    L="render --width 200 --height 140 --spp 400 --threads 1 --passes variance"
    "$BIN" $L --threads 0 --out long.pfm 2>/dev/null
    # stopped_run OUT CHECKPOINT SIGNAL WHOM: two ranks render to OUT with a checkpoint
    # after every tile; once it exists, SIGNAL goes to mpirun (WHOM 0) or to rank 1's
    # process alone (WHOM 1). Sets rc to mpirun's status; stderr in err.txt.
    stopped_run() {
        $MPIRUN -np 2 "$BIN" $L --out "$1" --checkpoint "$2" --checkpoint-interval 0 2>err.txt &
        pid=$!
        n=0
        while [ ! -s "$2" ] && [ $n -lt 1000 ]; do
            sleep 0.02
            n=$((n + 1))
        done
        target=$pid
        if [ "$4" = 1 ]; then
            target=
            for p in $(pgrep -f -- "--out $1"); do
                tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null |
                    grep -qx 'OMPI_COMM_WORLD_RANK=1' && target=$p
            done
            [ -n "$target" ] || fail "$3 to a worker: rank 1's process not found"
        fi
        kill -"$3" $target
        wait $pid
        rc=$?
    }
    stopped_run stopped.pfm ck TERM 0
    grep -q "tiles done" err.txt || fail "SIGTERM under MPI: not stopped early: $(cat err.txt)"
    [ -s stopped.pfm ] || fail "SIGTERM under MPI: no image"
    # SIGTERM to a worker rank alone stops the whole job as one to mpirun does: every rank
    # exits with 128 + 15, and rank 0 writes the image of the tiles done.
    stopped_run wstop.pfm wck TERM 1
    [ $rc -eq 143 ] || fail "SIGTERM to a worker: exit $rc, expected 143: $(cat err.txt)"
    [ -s wstop.pfm ] || fail "SIGTERM to a worker: no image of the tiles done"
    # A worker that dies (SIGKILL) ends the job without an image.
    stopped_run wkill.pfm kck KILL 1
    [ $rc -ne 0 ] || fail "SIGKILL to a worker: exit 0"
    [ -e wkill.pfm ] && fail "SIGKILL to a worker: an image was passed off as complete"
    $MPIRUN -np 3 "$BIN" $L --resume ck --out resumed.pfm 2>err.txt || fail "MPI resume: $(cat err.txt)"
    cmp -s long.pfm resumed.pfm || fail "MPI render resumed with 3 ranks differs from a single process"
    cmp -s long.variance.pfm resumed.variance.pfm ||
        fail "MPI render resumed with 3 ranks: the variance differs from a single process's"
    # One checkpoint format: the MPI checkpoint resumes in one process, and a checkpoint of
    # one process under mpirun, both to the uninterrupted image.
    "$BIN" $L --resume ck --out nompi.pfm 2>err.txt || fail "MPI checkpoint resumed in one process: $(cat err.txt)"
    cmp -s long.pfm nompi.pfm || fail "MPI checkpoint resumed in one process differs from a single process"
    cmp -s long.variance.pfm nompi.variance.pfm ||
        fail "MPI checkpoint resumed in one process: the variance differs"
    "$BIN" $L --spp 150 --checkpoint ck1 --out part.pfm 2>err.txt || fail "150 spp with a checkpoint: $(cat err.txt)"
    $MPIRUN -np 2 "$BIN" $L --resume ck1 --out frommain.pfm 2>err.txt || fail "single-process checkpoint under mpirun: $(cat err.txt)"
    cmp -s long.pfm frommain.pfm || fail "single-process checkpoint resumed under mpirun differs from a single process"
    cmp -s long.variance.pfm frommain.variance.pfm ||
        fail "single-process checkpoint resumed under mpirun: the variance differs"
fi

cli_end "mpi_check $PART"
