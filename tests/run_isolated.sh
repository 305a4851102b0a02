#!/bin/sh
# Runs a command in a private network namespace whose only interface is lo,
# with multicast routed there, so LCM test traffic never leaves this machine.
set -e
exec unshare -rn sh -c '
  ip link set lo up &&
  ip link set lo multicast on &&
  ip route add 224.0.0.0/4 dev lo &&
  PLSA_LCM_ISOLATED=1 LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0" exec "$@"' sh "$@"
