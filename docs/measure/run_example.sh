#!/bin/bash
# usage: REPO=... EXAMPLES=<crazyflie-lib-python>/examples RESULTS=<folder> run_example.sh PLANT EXAMPLE PORT
# Serves one drone (foranav crazyflie), runs one of Bitcraze's cflib examples unmodified against it (its URI from
# CFLIB_URI), appends "name rc= wall=" to $RESULTS/results.txt; the drone's tlog is in $RESULTS/<name>/drone0.tlog.
cd "$REPO"
PLANT=$1; EX=$2; PORT=$3; NAME=$(basename $EX .py)-$PLANT
OUT=$RESULTS/$NAME
.venv/bin/foranav crazyflie --plant $PLANT --crtp $PORT --max-time-s 75 --out $OUT > $OUT.server.log 2>&1 &
SP=$!
sleep 5
cd $EXAMPLES/$(dirname $EX)
START=$(date +%s.%N)
CFLIB_URI=udp://127.0.0.1:$PORT timeout 60 /work/i41/.venv/bin/python $(basename $EX) > $OUT.client.log 2>&1
RC=$?
END=$(date +%s.%N)
kill -TERM $SP; wait $SP
echo "$NAME rc=$RC wall=$(echo "$END - $START" | bc)" >> $RESULTS/results.txt
