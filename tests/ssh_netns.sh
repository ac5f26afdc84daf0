#!/usr/bin/env bash
# Test hosts for scripts/cluster.sh --hosts: three network namespaces joined by a bridge, each with
# its own address and its own sshd bound to that address only (generated host and user keys, root
# login by key). Root only.
#
#   tests/ssh_netns.sh up DIR     # prints HOST0,HOST1,HOSTC; DIR/ssh_config reaches them
#   tests/ssh_netns.sh down DIR   # stops the sshds, removes the namespaces and the bridge
set -uo pipefail
cmd=${1:-} dir=${2:-}
[ -n "$cmd" ] && [ -n "$dir" ] || { echo "usage: $0 up|down DIR" >&2; exit 2; }

down() {
  for f in "$dir"/sshd*.pid; do [ -s "$f" ] && kill "$(cat "$f")" 2>/dev/null; done
  [ -f "$dir/names" ] || return 0
  read -r tag net <"$dir/names"
  for i in 0 1 2; do  # whatever still runs in it (sshd's sessions, a test's leftovers), then the namespace
    for p in $(ip netns pids "${tag}$i" 2>/dev/null); do kill "$p" 2>/dev/null; done
    ip netns del "${tag}$i" 2>/dev/null
  done
  ip link del "${tag}br" 2>/dev/null
  rm -f "$dir/names"
  return 0
}
[ "$cmd" = down ] && { down; exit 0; }
[ "$cmd" = up ] || { echo "usage: $0 up|down DIR" >&2; exit 2; }
[ "$(id -u)" = 0 ] || { echo "error: needs root (network namespaces)" >&2; exit 1; }
[ -x /usr/sbin/sshd ] || { echo "error: needs /usr/sbin/sshd (Debian openssh-server)" >&2; exit 1; }
mkdir -p "$dir" /run/sshd
tag="ossh$(($$ % 100000))" net="10.78.$(($$ % 250)).$((($$ / 250) % 2 * 128))"
echo "$tag $net" >"$dir/names"
addr() { echo "${net%.*}.$((${net##*.} + $1))"; }  # .1 the bridge, .10-.12 the hosts
trap 'down; exit 1' ERR
set -e
ip link add "${tag}br" type bridge
ip addr add "$(addr 1)/25" dev "${tag}br"
ip link set "${tag}br" up
ssh-keygen -q -t ed25519 -N '' -f "$dir/host_key" <<<y >/dev/null
ssh-keygen -q -t ed25519 -N '' -f "$dir/user_key" <<<y >/dev/null
cp "$dir/user_key.pub" "$dir/authorized_keys"
: >"$dir/known_hosts"
hosts=()
for i in 0 1 2; do
  ns=${tag}$i a=$(addr $((10 + i)))
  ip netns add "$ns"
  ip link add "${tag}v$i" type veth peer name "${tag}p$i"
  ip link set "${tag}p$i" netns "$ns"
  ip link set "${tag}v$i" master "${tag}br" up
  ip -n "$ns" addr add "$a/25" dev "${tag}p$i"
  ip -n "$ns" link set "${tag}p$i" up
  ip -n "$ns" link set lo up
  cat >"$dir/sshd$i.conf" <<EOF
ListenAddress $a
HostKey $dir/host_key
AuthorizedKeysFile $dir/authorized_keys
PermitRootLogin prohibit-password
PasswordAuthentication no
KbdInteractiveAuthentication no
UsePAM no
StrictModes no
PidFile $dir/sshd$i.pid
EOF
  ip netns exec "$ns" /usr/sbin/sshd -f "$dir/sshd$i.conf" -E "$dir/sshd$i.log"
  echo "$a $(cut -d' ' -f1-2 "$dir/host_key.pub")" >>"$dir/known_hosts"
  hosts+=("$a")
done
cat >"$dir/ssh_config" <<EOF
Host *
  User root
  IdentityFile $dir/user_key
  IdentitiesOnly yes
  UserKnownHostsFile $dir/known_hosts
  StrictHostKeyChecking yes
  BatchMode yes
  ConnectTimeout 10
EOF
for a in "${hosts[@]}"; do  # each sshd answers
  for _ in $(seq 50); do ssh -F "$dir/ssh_config" "$a" true 2>/dev/null && break; sleep 0.1; done
  ssh -F "$dir/ssh_config" "$a" true
done
(IFS=,; echo "${hosts[*]}")
