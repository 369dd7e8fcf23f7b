# Sourced: brings up a private one-node Slurm (Debian's slurm-wlm and munge)
# under a scratch directory and takes it down again. Everything it starts has
# its own configuration, state, logs, ports and munge socket/key; it never
# reads or changes /etc/slurm, /etc/munge or a running system-wide Slurm, and
# it stops only the daemons it started, by PID.
#   slurm_up DIR      start munged, slurmctld, slurmd; export SLURM_CONF
#                     (returns non-zero with a one-line reason in SLURM_WHY)
#   slurm_down        cancel our jobs, stop our daemons (safe to call twice)
#   slurm_logs        print the tails of the daemons' logs (for failures)
# Settings that differ from a production Slurm, all to keep the test short:
#   cred_expire=5     a requeued job may start again after 5 s (default 120 s)
#   sched_interval=1  pending jobs are considered every second (default 60 s)
#   KillWait=5        5 s from SIGTERM to SIGKILL at the time limit (default 30 s)

SLURM_PIDS=()
SLURM_WATCHDOG=""

# Two free TCP ports on the loopback interface (the kernel picks them).
_slurm_free_ports() {
  /usr/bin/python3 - <<'PY'
import socket
socks = []
for _ in range(2):
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    socks.append(s)
print(" ".join(str(s.getsockname()[1]) for s in socks))
PY
}

# Reason to skip, or empty when this machine can run a private Slurm.
_slurm_missing() {
  local c
  for c in munged slurmctld slurmd sbatch squeue scontrol scancel sinfo; do
    command -v "$c" > /dev/null || { echo "$c not found (install slurm-wlm and munge)"; return; }
  done
  [ "$(id -u)" -eq 0 ] || echo "not root (slurmd must run as root to start jobs)"
}

_slurm_write_conf() {
  local dir=$1 ctld_port=$2 slurmd_port=$3 node=$4 hw=$5
  cat > "$dir/slurm.conf" <<CONF
ClusterName=snltest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/socket,cred_expire=5
SlurmUser=root
SlurmdUser=root
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1,bf_interval=1
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
KillWait=5
SlurmdParameters=config_overrides
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
TmpFS=$dir/tmp
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
NodeName=$node NodeAddr=127.0.0.1 $hw State=UNKNOWN
PartitionName=snltest Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
}

# munged with its own key, socket, pid, seed and log files under DIR/munge.
_slurm_start_munge() {
  local m=$1/munge
  mkdir -p "$m" && chmod 711 "$m"  # slurmd reaches the socket; the key stays 0400
  head -c 1024 /dev/urandom > "$m/key" && chmod 400 "$m/key"
  munged --foreground --force --socket="$m/socket" --key-file="$m/key" --pid-file="$m/pid" \
    --seed-file="$m/seed" --log-file="$m/log" > "$m/stdout" 2>&1 &
  SLURM_PIDS+=($!)
  for _ in $(seq 50); do [ -S "$m/socket" ] && return 0; sleep 0.1; done
  return 1
}

# Job processes and step daemons of this cluster that outlived it (a job that
# did not end when cancelled): they carry our SLURM_CONF in their environment,
# and SLURM_JOB_ID or the name slurmstepd. Killed by PID.
_slurm_kill_stragglers() {
  local f p pids=()
  for f in $(grep -lzxF "SLURM_CONF=$SLURM_CONF" /proc/[0-9]*/environ 2> /dev/null); do
    p=${f#/proc/}
    p=${p%/environ}
    if grep -qz '^SLURM_JOB_ID=' "$f" 2> /dev/null || [ "$(cat "/proc/$p/comm" 2> /dev/null)" = slurmstepd ]; then
      pids+=("$p")
    fi
  done
  [ ${#pids[@]} -gt 0 ] || return 0
  echo "private Slurm: killing leftover job processes ${pids[*]}" >&2
  kill "${pids[@]}" 2> /dev/null || true
  sleep 1
  kill -KILL "${pids[@]}" 2> /dev/null || true
}

# Runs in the background: if the test shell dies without its cleanup (ctest
# kills it at its timeout), cancel the jobs and stop the daemons anyway.
_slurm_watchdog() {
  local owner=$1 p
  shift
  while kill -0 "$owner" 2> /dev/null; do sleep 2; done
  timeout 10 scancel --quiet --user="$(id -un)" 2> /dev/null || true
  sleep 3
  for p in "$@"; do kill "$p" 2> /dev/null || true; done
  sleep 3
  for p in "$@"; do kill -KILL "$p" 2> /dev/null || true; done
  _slurm_kill_stragglers
}

slurm_up() {
  SLURM_DIR=$1
  SLURM_WHY=$(_slurm_missing)
  [ -z "$SLURM_WHY" ] || return 1
  # Never talk to another cluster: forget any Slurm job or configuration we run in.
  local v
  for v in $(env | sed -n 's/^\(SLURM_[A-Z_]*\)=.*/\1/p'); do unset "$v"; done
  mkdir -p "$SLURM_DIR"/{state,spool,log,tmp}
  local node hw ports
  node=$(hostname -s)
  # The node's real sockets/cores/threads, so that slurmd accepts the configuration.
  hw=$(slurmd -C 2> /dev/null | head -1 | tr ' ' '\n' | grep -E '^(CPUs|Boards|SocketsPerBoard|CoresPerSocket|ThreadsPerCore)=' | tr '\n' ' ')
  ports=$(_slurm_free_ports)
  # shellcheck disable=SC2086
  _slurm_write_conf "$SLURM_DIR" $ports "$node" "$hw"
  export SLURM_CONF=$SLURM_DIR/slurm.conf
  _slurm_start_munge "$SLURM_DIR" || { SLURM_WHY="munged did not start: $(tail -1 "$SLURM_DIR/munge/stdout")"; return 1; }
  slurmctld -D -f "$SLURM_CONF" > "$SLURM_DIR/log/slurmctld.stdout" 2>&1 &
  SLURM_PIDS+=($!)
  slurmd -D -f "$SLURM_CONF" -N "$node" > "$SLURM_DIR/log/slurmd.stdout" 2>&1 &
  SLURM_PIDS+=($!)
  _slurm_watchdog $$ "${SLURM_PIDS[@]}" > /dev/null 2>&1 &
  SLURM_WATCHDOG=$!
  local d state=""
  for _ in $(seq 60); do
    # A daemon that exits at once says why in its log; do not wait for it.
    for d in slurmctld:1 slurmd:2; do
      kill -0 "${SLURM_PIDS[${d#*:}]}" 2> /dev/null && continue
      d=${d%:*}
      SLURM_WHY="$d exited at start: $(cat "$SLURM_DIR/log/$d.log" "$SLURM_DIR/log/$d.stdout" 2> /dev/null |
        grep -m1 -E 'error|fatal')"
      return 1
    done
    state=$(timeout 5 sinfo -h -n "$node" -o %t 2> /dev/null || true)
    case $state in idle*|mix*|alloc*) return 0;; esac
    sleep 0.5
  done
  SLURM_WHY="the private Slurm did not come up in 30 s (node state '${state:-none}'; logs in $SLURM_DIR/log)"
  return 1
}

slurm_down() {
  [ ${#SLURM_PIDS[@]} -gt 0 ] || return 0
  local p
  [ -z "$SLURM_WATCHDOG" ] || kill "$SLURM_WATCHDOG" 2> /dev/null || true
  SLURM_WATCHDOG=""
  if [ ${#SLURM_PIDS[@]} -gt 1 ] && kill -0 "${SLURM_PIDS[1]}" 2> /dev/null; then  # slurmctld is up
    timeout 10 scancel --quiet --user="$(id -un)" 2> /dev/null || true
    for _ in $(seq 40); do
      [ -z "$(timeout 5 squeue -h -o %i 2> /dev/null)" ] && break
      sleep 0.25
    done
  fi
  for p in "${SLURM_PIDS[@]}"; do kill "$p" 2> /dev/null || true; done
  for p in "${SLURM_PIDS[@]}"; do
    for _ in $(seq 40); do kill -0 "$p" 2> /dev/null || break; sleep 0.25; done
    kill -KILL "$p" 2> /dev/null || true
    wait "$p" 2> /dev/null || true
  done
  _slurm_kill_stragglers
  SLURM_PIDS=()
}

slurm_logs() {
  local f
  for f in "$SLURM_DIR"/log/*.log "$SLURM_DIR"/log/*.stdout "$SLURM_DIR"/munge/stdout; do
    [ -s "$f" ] && { echo "---- $f"; tail -n 15 "$f"; }
  done
}
