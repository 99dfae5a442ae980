#!/bin/bash
# Re-runs of the docs' single-episode commands (session 44), JSON into results/docs_s44.
set -u
# Run from the repository root with rrtdrive installed: bash results/docs_s44/rerun.sh
D=results/docs_s44
for c in pure-pursuit stanley lqr; do
  rrtdrive simulate parking --seed 25 --deterministic --controller $c --json $D/parking_seed25_$c.json > /dev/null 2>&1
done
rrtdrive simulate parking --reverse-in --planner hybrid-a-star --deterministic --controller pure-pursuit --trajectory $D/hybrid_parking_reverse_in.csv --json $D/hybrid_parking_reverse_in.json > /dev/null 2>&1
rrtdrive simulate parallel-parking --planner hybrid-a-star --deterministic --controller pure-pursuit --trajectory $D/hybrid_parallel_parking.csv --json $D/hybrid_parallel_parking.json > /dev/null 2>&1
rrtdrive simulate u-turn --planner hybrid-a-star --deterministic --controller pure-pursuit --trajectory $D/hybrid_u_turn.csv --json $D/hybrid_u_turn.json > /dev/null 2>&1
for c in pure-pursuit stanley lqr; do
  rrtdrive simulate garage --reverse --start 28.7,3.905,-1.5707963 --goal 33.9,16.095,1.5707963 --controller $c --json $D/garage_bay_to_bay_$c.json > /dev/null 2>&1
done
python -c "from rrtdrive.tight_maps import kerbside_map; from rrtdrive.maps import save_map; save_map(kerbside_map(1.4), '/tmp/kerb14.json')"
for c in pure-pursuit stanley lqr; do
  rrtdrive simulate /tmp/kerb14.json --reverse --controller $c --json $D/kerb14_$c.json > /dev/null 2>&1
done
/usr/bin/time -f "%e s %M KB" rrtdrive simulate parking-v0 --seed 3 --video /tmp/x.mp4 --json $D/parking_v0_seed3_video.json > /dev/null 2> /tmp/pv0.err; tail -1 /tmp/pv0.err > $D/parking_v0_seed3_time.txt
python results/docs_s24/creeping.py $D/hybrid_*.csv > $D/creeping.txt
echo done
