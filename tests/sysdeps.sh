#!/bin/sh
# Installs the system packages the tests need (`make test` runs this first): the
# TS-7800 (ARMv5TE) and TS-5500 (i486) toolchains, qemu-user to run their builds on the
# boards' CPU models, valgrind for the runtime bench, clang with libFuzzer for the fuzz
# tests, musl built for the i486 (runtime/musl-i486.sh), and chromium for the report's
# browser test (Playwright, from the test extra, drives it).
#
# Another package manager holding the lock is waited for (LOCK_WAIT_S), not a reason to
# give up. Under CI=true whatever cannot be installed fails the run (exit 1); elsewhere
# this says what is missing and why, and the tests that need it are reported as skipped.
set -u

PACKAGES="gcc make gcc-arm-linux-gnueabi libc6-dev-armel-cross gcc-i686-linux-gnu libc6-dev-i386-cross
          qemu-user valgrind clang libclang-rt-dev chromium"
MUSL_PREFIX=${MUSL_PREFIX:-/usr/local/lib/musl-i486}  # where musl for the i486 lives
LOCK_WAIT_S=${LOCK_WAIT_S:-900}
root=$(cd "$(dirname "$0")/.." && pwd)

case ${CI:-} in true | 1) ci=1 ;; *) ci= ;; esac

give_up() {
    if [ -n "$ci" ]; then
        echo "sysdeps: $1 (CI=true: every tool the tests need must be installed)" >&2
        exit 1
    fi
    echo "sysdeps: $1; the tests that need it will be skipped" >&2
    exit 0
}

# apt-get, retried while another package manager holds a lock: dpkg's lock is waited for
# by apt itself (DPkg::Lock::Timeout), the package lists' lock is not.
apt_get() {
    waited=0
    while :; do
        if out=$($sudo env DEBIAN_FRONTEND=noninteractive apt-get -qq \
            -o DPkg::Lock::Timeout="$LOCK_WAIT_S" "$@" 2>&1); then
            return 0
        fi
        case $out in
        *"Could not get lock"* | *"Unable to lock"*)
            if [ "$waited" -ge "$LOCK_WAIT_S" ]; then
                echo "$out" >&2
                return 1
            fi
            [ "$waited" -eq 0 ] && echo "sysdeps: waiting for another package manager" >&2
            sleep 5
            waited=$((waited + 5))
            ;;
        *)
            echo "$out" >&2
            return 1
            ;;
        esac
    done
}

missing=$(for p in $PACKAGES; do dpkg -s "$p" >/dev/null 2>&1 || echo "$p"; done | xargs)
# An install from before -mpc64 worked with it (its start file, strtod and printf at
# extended precision) is built again.
if command -v i486-linux-musl-gcc >/dev/null &&
    grep -q crtprec64 "$MUSL_PREFIX/lib/musl-gcc.specs" 2>/dev/null &&
    grep -q __floatscan_x87 "$MUSL_PREFIX/lib/libc.a" 2>/dev/null; then
    musl=
else
    musl=1
fi
[ -z "$missing" ] && [ -z "$musl" ] && exit 0

if [ "$(id -u)" = 0 ]; then
    sudo=
elif command -v sudo >/dev/null && sudo -n true 2>/dev/null; then
    sudo="sudo -n"
else
    give_up "cannot install ${missing:-musl for the i486} (not root, no sudo)"
fi

if [ -n "$missing" ]; then
    echo "sysdeps: installing $missing" >&2
    apt_get update && apt_get install -y --no-install-recommends $missing ||
        give_up "could not install $missing"
fi
if [ -n "$musl" ]; then
    echo "sysdeps: building musl for the i486 (about a minute)" >&2
    $sudo sh "$root/runtime/musl-i486.sh" "$MUSL_PREFIX" /usr/local/bin ||
        give_up "could not build musl for the i486 (runtime/musl-i486.sh)"
fi
