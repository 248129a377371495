#!/usr/bin/env bash
# Background chain on the device: PART=a (build, synth, radii) then PART=b (bricks from points), logs in /tmp/w17h.
mkdir -p /tmp/w17h/out
( OUT=/tmp/w17h/out PART=a bash .device-deps/gpu17h.sh; OUT=/tmp/w17h/out PART=b bash .device-deps/gpu17h.sh; echo CHAIN-DONE ) > /tmp/w17h/chain.log 2>&1
