#!/bin/sh
# Builds musl, the C library the TS-5500 binary links, for the i486 and installs the
# compiler wrapper `i486-linux-musl-gcc` that `gliderplan compile --target ts5500` runs.
#
# Why: the distribution's 32-bit x86 C libraries are built for the i686 and use its
# instructions (cmov in the start-up code, fucomi in libm); the TS-5500's AMD Elan SC520
# is a 486-class core and dies on them with SIGILL. musl needs only Linux system calls
# of the 2.6 kernels (with fallbacks for older ones) and builds for the i486 as it is.
#
#   sh musl-i486.sh PREFIX [BINDIR]    # e.g. /usr/local/lib/musl-i486 /usr/local/bin
#
# Needs the i686 cross compiler (Debian: gcc-i686-linux-gnu) and apt-get: the source is
# the distribution's own source package, fetched through a private copy of the
# configured package sources (nothing on the system changes but PREFIX and BINDIR).
set -eu

prefix=${1:?usage: musl-i486.sh PREFIX [BINDIR]}
bindir=${2:-$prefix/bin}
cross=i686-linux-gnu-

command -v "${cross}gcc" >/dev/null || {
    echo "musl-i486: ${cross}gcc is missing (Debian: apt-get install gcc-i686-linux-gnu)" >&2
    exit 1
}

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/lists/partial" "$work/parts" "$work/src"

# The configured package sources, as source-package sources.
for list in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [ -f "$list" ] && sed -n 's/^deb /deb-src /p' "$list"
done >"$work/parts/distribution.list"
for sources in /etc/apt/sources.list.d/*.sources; do
    [ -f "$sources" ] && sed 's/^Types:.*/Types: deb-src/' "$sources" \
        >"$work/parts/$(basename "$sources")"
done
apt="apt-get -qq -o Dir::Etc::SourceList=/dev/null -o Dir::Etc::SourceParts=$work/parts
     -o Dir::State::Lists=$work/lists -o APT::Sandbox::User=root"
# A source list that fails (a third-party repository without sources) is no reason to stop
# as long as musl's source arrives.
$apt update >"$work/update.log" 2>&1 || true
(cd "$work/src" && $apt source --download-only musl >"$work/source.log" 2>&1) || {
    echo "musl-i486: cannot fetch musl's source package:" >&2
    cat "$work/update.log" "$work/source.log" >&2
    exit 1
}
tar -xzf "$work"/src/musl_*.orig.tar.gz -C "$work/src"
cd "$work"/src/musl-*/

# The TS-5500 build's -mpc64 sets the x87 to double precision for the whole program (its
# arithmetic then rounds each result once, as the reference semantics do). musl reads and
# prints numbers (strtod, printf) in long double and needs the 64-bit mantissa for that:
# those two routines get it for the duration of the call.
with_extended_precision() {  # FILE 'DEFINITION LINE' NAME 'ARGUMENTS OF THE CALL'
    awk -v line="$2" -v name="$3" -v args="$4" '
        $0 == line && !done {
            renamed = line
            sub(name "\\(", name "_x87(", renamed)
            call = name "_x87(" args ")"
            print renamed ";"
            print line
            print "{"
            print "\tunsigned short saved, extended;"
            print "\t__asm__ volatile (\"fnstcw %0\" : \"=m\"(saved) : : \"memory\");"
            print "\textended = saved | 0x300;"
            print "\t__asm__ volatile (\"fldcw %0\" : : \"m\"(extended) : \"memory\");"
            print "\t__typeof__(" call ") result = " call ";"
            print "\t__asm__ volatile (\"fldcw %0\" : : \"m\"(saved) : \"memory\");"
            print "\treturn result;"
            print "}"
            print renamed
            done = 1
            next
        }
        { print }
        END { if (!done) exit 1 }' "$1" >"$1.new" && mv "$1.new" "$1" || {
        echo "musl-i486: '$2' not found in $1 (another musl version?)" >&2
        exit 1
    }
}
with_extended_precision src/internal/floatscan.c \
    'long double __floatscan(FILE *f, int prec, int pok)' __floatscan 'f, prec, pok'
with_extended_precision src/stdio/vfprintf.c \
    'static int fmt_fp(FILE *f, long double y, int w, int p, int fl, int t)' fmt_fp \
    'f, y, w, p, fl, t'

./configure --target=i386 --prefix="$prefix" --disable-shared --enable-wrapper=gcc \
    CROSS_COMPILE="$cross" CC="${cross}gcc" CFLAGS="-march=i486 -O2" >"$work/build.log" 2>&1 &&
    make -j"$(nproc)" >>"$work/build.log" 2>&1 &&
    make install >>"$work/build.log" 2>&1 || {
    tail -n 30 "$work/build.log" >&2
    echo "musl-i486: the build failed" >&2
    exit 1
}
# musl's specs replace gcc's start files, and with them the object that sets the x87's
# precision for -mpc64; put it back.
sed -i '/^\*startfile:$/{n;s/$/ %{mpc32:crtprec32.o%s} %{mpc64:crtprec64.o%s} %{mpc80:crtprec80.o%s}/}' \
    "$prefix/lib/musl-gcc.specs"
mkdir -p "$bindir"
ln -sf "$prefix/bin/musl-gcc" "$bindir/i486-linux-musl-gcc"
echo "musl-i486: musl $(cat VERSION) for the i486 in $prefix; compiler $bindir/i486-linux-musl-gcc"
