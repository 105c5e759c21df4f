#!/bin/bash
cd /work/main
for enc in rlcard strength; do
  rm -rf /work/runs/qs/$enc
  echo "$enc start $(date +%s.%N) load $(cut -d' ' -f1 /proc/loadavg)" >> /work/runs/qs/times.txt
  /usr/bin/time -v .venv/bin/pokerirl study irc-199504 --preset quick --encoding $enc --out /work/runs/qs/$enc > /work/runs/qs/$enc.log 2> /work/runs/qs/$enc.err
  echo "$enc end $(date +%s.%N) rc $? load $(cut -d' ' -f1 /proc/loadavg)" >> /work/runs/qs/times.txt
done
