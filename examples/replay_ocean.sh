#!/bin/sh
# Fly the thermocline survey through the water a real Slocum glider logged.
#
#   examples/replay_ocean.sh LOGDIR [RUNDIR]
#
# LOGDIR holds the glider's science logs (*.ebd; with their `cac/` sensor caches and,
# for the latitude, the flight logs *.dbd). Each logged dive and climb becomes a cast
# of temperature and salinity (TEOS-10) against depth; the simulated glider meets them
# in the order and at the times the real one did. The run's files go to RUNDIR
# (default out/replay): depth.png shows the track over the replayed water.
set -eu
if [ $# -lt 1 ]; then
    echo "usage: $0 LOGDIR [RUNDIR]" >&2
    exit 2
fi
here=$(dirname "$0")
gp=${GLIDERPLAN:-$here/../.venv/bin/gliderplan}
"$gp" sim "$here/thermocline_survey.mission" --ocean "$1" --duration 6h \
    -o "${2:-out/replay}"
