#!/bin/sh
# --resume on an OpenCL device (PoCL; registered only in builds with the OpenCL backend):
# the film lives on the host after a resume and every pass is added to it from the
# cleared device film; the result is the bits of an uninterrupted render on the device,
# passes included, also when the resume asks for more samples than the checkpoint had.
# Usage: cli_opencl_resume.sh TRAC0R_BINARY SCRATCH_DIR
set -u
. "$(dirname "$0")/common.sh"
cli_begin "$1" "$2"

R="render --width 48 --height 32 --device opencl --passes albedo,id"
"$BIN" $R --spp 30 --out full.pfm 2>err.txt || fail "uninterrupted: $(cat err.txt)"
"$BIN" $R --spp 12 --checkpoint ck --out part.pfm 2>err.txt || fail "first part: $(cat err.txt)"
cmp -s full.pfm part.pfm && fail "12 and 30 samples give the same image: the test proves nothing"
"$BIN" $R --resume ck --spp 30 --out resumed.pfm 2>err.txt || fail "resume: $(cat err.txt)"
for f in "" .albedo .id; do
    cmp -s full$f.pfm resumed$f.pfm || fail "resumed$f.pfm differs from the uninterrupted render"
done

cli_end cli_opencl_resume
