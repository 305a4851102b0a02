#!/usr/bin/env bash
# The Java LCM types decode what plsa records: a simulated run as an LCM
# event log, read by lcm.jar's log reader and the generated classes (what
# lcm-spy uses), against the same log converted to CSV by plsa.
#   decode_log.sh <plsa> <java> <class path>
set -euo pipefail
plsa=$1 java=$2 classpath=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$plsa" simulate --experiment joystick --duration 2 --seed 2 --out "$work/run.lcmlog" > /dev/null
"$plsa" convert --in "$work/run.lcmlog" --out "$work/run.csv" > /dev/null
"$java" -cp "$classpath" DecodePlsaLog "$work/run.lcmlog" > "$work/java.txt"
rows=$(grep -vc '^#\|^time_s' "$work/run.csv")
states=$(sed -n 's/^states //p' "$work/java.txt")
[ "$states" = "$rows" ] || { echo "Java decoded $states states, the CSV has $rows rows"; exit 1; }
# Each state's bend and steer, as Java prints them, against the CSV's columns (same shortest digits).
paste -d' ' <(grep -v '^states' "$work/java.txt" | awk '{print $3, $4}') \
  <(grep -v '^#\|^time_s' "$work/run.csv" | awk -F, '{print $8, $9}') |
  awk '$1 != $3 || $2 != $4 { bad++; if (bad < 4) print "row " NR ": Java " $1 " " $2 ", CSV " $3 " " $4 } END { exit bad > 0 }'
echo "Java decoded all $states states as plsa wrote them"
