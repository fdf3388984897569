#!/usr/bin/env bash
# build-sdcc.sh: builds the segment firmware for the 8051 with SDCC.
#
#   firmware-segment/c-shim/build-sdcc.sh [all|lpc938|s51]     (default: all)
#
#   lpc938  segment.c + lpc938/main.c -> $BUILD_DIR/lpc938/segment-lpc938.ihx, prints the code,
#           internal RAM and external RAM used, and exits nonzero when the program does not
#           fit the P89LPC938 (8 KB flash, 256 B internal RAM, 512 B auxiliary RAM) or leaves
#           less than MIN_STACK bytes of internal RAM for the stack.
#   s51     segment.c + s51/vectors_main.c -> $BUILD_DIR/s51/vectors.ihx, the test harness for
#           the s51 simulator (tests/tests/s51_vectors.rs runs it).
#
# BUILD_DIR defaults to firmware-segment/c-shim/build (gitignored).
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
BUILD_DIR="${BUILD_DIR:-$HERE/build}"
TARGET="${1:-all}"

FLASH_MAX=8192
IRAM_MAX=256
XRAM_MAX=512
# Stack floor: the SI interrupt (highest priority) can nest on the timer or keypad interrupt on
# top of the main loop's deepest call. SI: 2 (vector) + 13 (ACC, B, DPTR, PSW, R0-R7 saved
# because it calls functions) + 8 (seg_target_step -> seg_latch -> seg_pec_update / _gptrget);
# timer or KBI: 2 + about 6; main: about 6 (store_address -> eeprom_write, or a segment.c
# call -> _gptrget). About 37 bytes: require 48.
MIN_STACK="${MIN_STACK:-48}"

# --nooverlay: the SI interrupt routine calls segment.c; SDCC must not overlay the locals of
# leaf functions the interrupt reaches with those of the main loop's leaf functions.
CFLAGS=(-mmcs51 --model-small --std-c11 --nooverlay -I"$HERE/include")

if ! command -v sdcc >/dev/null 2>&1; then
    echo "build-sdcc.sh: sdcc not found; install it: apt-get install sdcc sdcc-ucsim" >&2
    exit 2
fi

compile() { # out_dir source...
    local out="$1"
    shift
    local src
    for src in "$@"; do
        sdcc "${CFLAGS[@]}" -c "$src" -o "$out/"
    done
}

# Prints the sizes from SDCC's .mem file and fails when they exceed the LPC938.
check_sizes() { # mem_file
    local mem="$1"
    local code iram stack xram
    code=$(awk '/ROM\/EPROM\/FLASH/ {print $(NF-1)}' "$mem")
    xram=$(awk '$1 == "EXTERNAL" && $2 == "RAM" {print $(NF-1)}' "$mem")
    # Internal RAM map: every cell that is not free (blank) and not stack (S) is in use.
    iram=$(awk -F'|' '/^0x[0-9a-f]0:\|/ {for (i = 2; i <= 17; i++) if ($i != " " && $i != "S") n++} END {print n + 0}' "$mem")
    stack=$(sed -n 's/^Stack starts at.*with \([0-9]*\) bytes available.*/\1/p' "$mem")
    stack="${stack:-0}"
    echo "code (ROM/EPROM/FLASH): $code bytes of $FLASH_MAX"
    echo "internal RAM (data, idata, register banks, bits): $iram bytes of $IRAM_MAX (stack: $stack bytes free)"
    echo "external RAM (xdata): $xram bytes of $XRAM_MAX"
    local fail=0
    if [ "$code" -gt "$FLASH_MAX" ]; then echo "FAIL: code does not fit $FLASH_MAX B flash" >&2; fail=1; fi
    if [ "$iram" -gt "$IRAM_MAX" ]; then echo "FAIL: internal RAM over $IRAM_MAX B" >&2; fail=1; fi
    if [ "$stack" -lt "$MIN_STACK" ]; then echo "FAIL: only $stack B left for the stack (need $MIN_STACK)" >&2; fail=1; fi
    if [ "$xram" -gt "$XRAM_MAX" ]; then echo "FAIL: xdata over $XRAM_MAX B" >&2; fail=1; fi
    return "$fail"
}

build_lpc938() {
    local out="$BUILD_DIR/lpc938"
    rm -rf "$out"
    mkdir -p "$out"
    compile "$out" "$HERE/lpc938/main.c" "$HERE/src/segment.c"
    # The linker limits make SDCC itself refuse a program that overflows the part.
    if ! sdcc "${CFLAGS[@]}" --code-size "$FLASH_MAX" --iram-size "$IRAM_MAX" --xram-size "$XRAM_MAX" \
        "$out/main.rel" "$out/segment.rel" -o "$out/segment-lpc938.ihx"; then
        echo "FAIL: the LPC938 link failed (over $FLASH_MAX B flash, $IRAM_MAX B internal RAM or $XRAM_MAX B xdata?)" >&2
        exit 1
    fi
    echo "== P89LPC938: $out/segment-lpc938.ihx"
    # Runtime-library modules linked: SDCC's arithmetic helpers (_mulint, _divuint, ...) are
    # not reentrant in the small model, so none may be reached from both an interrupt and
    # the main loop. List them so a new one is noticed.
    echo "runtime library modules: $(sed -n 's/.*\[ \(.*\)\.rel \].*/\1/p' "$out/segment-lpc938.map" | sort -u | tr '\n' ' ')"
    check_sizes "$out/segment-lpc938.mem"
}

build_s51() {
    local out="$BUILD_DIR/s51"
    rm -rf "$out"
    mkdir -p "$out"
    compile "$out" "$HERE/s51/vectors_main.c" "$HERE/src/segment.c"
    sdcc "${CFLAGS[@]}" "$out/vectors_main.rel" "$out/segment.rel" -o "$out/vectors.ihx"
    echo "== s51 harness: $out/vectors.ihx"
}

case "$TARGET" in
    all)
        build_lpc938
        build_s51
        ;;
    lpc938) build_lpc938 ;;
    s51) build_s51 ;;
    *)
        echo "usage: $0 [all|lpc938|s51]" >&2
        exit 2
        ;;
esac
