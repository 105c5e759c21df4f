#!/bin/bash
# usage: run.sh TREE TAG ENC...
tree=$1; tag=$2; shift 2
cd $tree
for enc in "$@"; do
  out=/work/runs/qs2/$tag-$enc
  rm -rf $out
  s=$(date +%s.%N); l=$(cut -d' ' -f1 /proc/loadavg)
  PYTHONPATH=$tree /work/main/.venv/bin/python -m pokerirl study irc-199504 --preset quick --encoding $enc --out $out > $out.log 2> $out.err
  rc=$?
  e=$(date +%s.%N)
  echo "$tag $enc wall $(echo "$e - $s" | bc) rc $rc load $l -> $(cut -d' ' -f1 /proc/loadavg)" >> /work/runs/qs2/times.txt
done
