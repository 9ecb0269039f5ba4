#!/bin/sh
# SPDX-License-Identifier: BSD-3-Clause
# tests/slurm/run.sh SANDSLIDE_MPI SANDSLIDE - a real Slurm on this one
# machine (make MPI=1 test-slurm, CI): munged, slurmctld and slurmd started
# from a slurm.conf written for this node, the job of doc/cluster.md#slurm
# (tests/slurm/job.sh) submitted with sbatch --wait as 2 tasks x 1 CPU and
# as 1 task x 2 CPUs, each output compared with the serial build's bit for
# bit (tools/compare_outputs.py).  The daemons are stopped at the end
# whatever happened; on a failure their logs are printed.
#
# Debian's packages (make deps-slurm): slurmctld, slurmd, slurm-client,
# munge, libpmix-dev.  Everything runs as root in a temporary folder with its own munge
# key and socket and its own ports (SANDSLIDE_SLURM_PORT, default 16817,
# and the next one), so a Slurm or munged already on the machine is left
# alone.  The settings suit a container: no systemd, no cgroups.
# SANDSLIDE_SLURM_KEEP=1 keeps the folder (configuration, logs, outputs).
set -eu

[ $# -eq 2 ] || { echo "usage: $0 SANDSLIDE_MPI SANDSLIDE" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
mpi_bin=$(realpath "$1")
serial_bin=$(realpath "$2")
port=${SANDSLIDE_SLURM_PORT:-16817}

for c in munged mungekey slurmctld slurmd sbatch sinfo srun scontrol; do
	command -v "$c" >/dev/null || {
		echo "test-slurm: '$c' not found: install Debian's Slurm and munge (make deps-slurm)" >&2
		exit 1
	}
done
[ "$(id -u)" = 0 ] || { echo "test-slurm: run as root (slurmd must be root to start a job's tasks as their user)" >&2; exit 1; }
/usr/bin/python3 -c 'import h5py' 2>/dev/null ||
	{ echo "test-slurm: h5py not found: tools/compare_outputs.py needs it (make deps-test)" >&2; exit 1; }

tmp=$(mktemp -d /tmp/sandslide-slurm.XXXXXX)
# munged wants its socket's folders open to all (it warns otherwise);
# nothing in them is secret but the key, which is 0600
chmod 755 "$tmp"
pids=""
ok=0
stop() {
	# a job still running (a timeout, a signal) cancelled first: its tasks
	# are slurmstepd's, which outlive slurmd; then the daemons, by the pids
	# we started; then their logs if it failed (to the end even if whoever
	# reads them has gone: a closed pipe)
	trap '' PIPE
	if [ $ok = 0 ] && [ -n "${SLURM_CONF:-}" ] && [ -n "$(squeue -h -o %i 2>/dev/null)" ]; then
		scancel --full -u root 2>/dev/null || true
		n=0
		while [ -n "$(squeue -h -o %i 2>/dev/null)" ] && [ $n -lt 100 ]; do sleep 0.1; n=$((n + 1)); done
	fi
	for p in $pids; do kill "$p" 2>/dev/null || true; done
	for p in $pids; do
		n=0
		while kill -0 "$p" 2>/dev/null && [ $n -lt 50 ]; do sleep 0.1; n=$((n + 1)); done
		kill -9 "$p" 2>/dev/null || true
	done
	if [ $ok = 0 ]; then
		for f in "$tmp"/slurmctld.log "$tmp"/slurmd.log "$tmp"/*.err; do
			[ -s "$f" ] || continue
			echo "---- $f (last 40 lines)"
			tail -n 40 "$f"
		done
	fi
	if [ -n "${SANDSLIDE_SLURM_KEEP:-}" ]; then echo "test-slurm: kept $tmp"; else rm -rf "$tmp"; fi
}
trap stop EXIT
trap 'exit 1' INT TERM HUP

fail() { echo "test-slurm: FAILED: $*" >&2; exit 1; }

# ---- munge: a key of our own, and munged on a socket of our own ----------
mkdir -p "$tmp/munge"
# (in the foreground munged logs to stderr; --force: it runs as root)
mungekey --create --keyfile="$tmp/munge/munge.key"
munged --foreground --force --socket="$tmp/munge/socket" --key-file="$tmp/munge/munge.key" \
	--pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/seed" >"$tmp/munged.err" 2>&1 &
pids="$pids $!"

# ---- slurm.conf for this node --------------------------------------------
host=$(hostname -s)
cpus=$(nproc)
# both jobs take 2 CPUs; on 1 they would wait for ever
[ "$cpus" -ge 2 ] || fail "the jobs need 2 CPUs, nproc says $cpus"
# MB, as slurmd counts it; a little under MemTotal, so that the node is not
# drained for having less memory than configured
mem=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 * 0.95 }' /proc/meminfo)
mkdir -p "$tmp/state" "$tmp/spool" "$tmp/job1" "$tmp/job2"
cat >"$tmp/slurm.conf" <<EOF
# written by tests/slurm/run.sh for one node: $host, $cpus CPUs, $mem MB
ClusterName=sandslide-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
# root runs everything: the daemons, and the job (its submitter)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge/socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# no systemd and no cgroups in a container: processes tracked through
# /proc, tasks not bound, nothing accounted
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
# CPUs are what is handed out, one per task
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
MpiDefault=none
# the node is what this file says, whatever slurmd finds (a container may
# show the host's sockets, or a cgroup's fewer CPUs)
SlurmdParameters=config_overrides
ReturnToService=2
# sbatch --wait polls the job after 2 s, then backs off to 8 and 32 s
# unless MinJobAge / 2 is at most 2 (sbatch.c, _job_wait): a job of 3 s
# would take 10 s.  4 keeps the poll at 2 s, and a finished job's record
# for 4 s, two polls (0 is refused: "MinJobAge must be at least 2").
MinJobAge=4
# no mail is sent (the default program is not installed)
MailProg=/bin/true
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=10 State=UP
EOF
export SLURM_CONF="$tmp/slurm.conf"

# ---- the daemons, in the foreground of background jobs -------------------
slurmctld -D -i -f "$SLURM_CONF" >"$tmp/slurmctld.err" 2>&1 &
pids="$pids $!"
slurmd -D -f "$SLURM_CONF" >"$tmp/slurmd.err" 2>&1 &
pids="$pids $!"

# the node idle within 30 s (sinfo itself waits for slurmctld to answer)
t0=$(date +%s%N)
n=0
state=""
while [ $n -lt 300 ]; do
	state=$(sinfo -h -n "$host" -o %t 2>/dev/null || true)
	[ "$state" = idle ] && break
	for p in $pids; do kill -0 "$p" 2>/dev/null || fail "a daemon exited (pid $p): see its log"; done
	sleep 0.1
	n=$((n + 1))
done
[ "$state" = idle ] || fail "node $host not idle after 30 s (sinfo says '$state')"
echo "test-slurm: slurmctld and slurmd up, node $host idle ($cpus CPUs) after $((($(date +%s%N) - t0) / 1000000)) ms"

# ---- the serial reference -------------------------------------------------
cp "$root/cases/dem/terrain.asc" "$tmp/dem.asc"
(cd "$tmp" && "$serial_bin" relax dem.asc -o serial.h5 --threads 1 --max-time 2000 -q) ||
	fail "the serial relax failed"

# ---- the job, as 2 tasks x 1 CPU and as 1 task x 2 CPUs -------------------
# Open MPI's settings for a container without RDMA
# (doc/cluster.md#open-mpi-as-root-on-a-small-machine), exported to the job
# by sbatch; srun starts the ranks, so nothing asks for mpirun's root check
export OMPI_MCA_mpi_yield_when_idle=1 OMPI_MCA_btl_vader_single_copy_mechanism=none \
	OMPI_MCA_pml=ob1 OMPI_MCA_btl=self,vader OMPI_MCA_btl_base_warn_component_unused=0
# OpenMP threads that sleep when they wait: a 2-thread rank whose threads
# spin while another program holds one of the 2 cores took 5 to 28 s
# instead of 0.5 (load average 6 to 8, the same bits either way)
export OMP_WAIT_POLICY=PASSIVE
export SANDSLIDE_MPI="$mpi_bin"
job=0
for layout in 2x1 1x2; do
	tasks=${layout%x*}
	threads=${layout#*x}
	job=$((job + 1))
	d="$tmp/job$job"
	cp "$tmp/dem.asc" "$d/dem.asc"
	t0=$(date +%s%N)
	timeout 120 sbatch --wait --parsable --chdir="$d" --output="$d/slurm.out" \
		--ntasks="$tasks" --cpus-per-task="$threads" "$here/job.sh" >"$d/sbatch.out" 2>"$tmp/sbatch$job.err" ||
		{ cat "$d/slurm.out" 2>/dev/null; fail "sbatch --wait ($tasks tasks x $threads CPUs) failed: $(cat "$tmp/sbatch$job.err")"; }
	id=$(cat "$d/sbatch.out")
	echo "test-slurm: job $id ($tasks tasks x $threads CPUs) done in $((($(date +%s%N) - t0) / 1000000)) ms; its output:"
	sed 's/^/    /' "$d/slurm.out"
	# one summary: rank 0 alone prints.  Two would be two one-rank runs
	# that never formed one MPI job (srun without its MPI plugin).
	n=$(grep -c '^wrote relaxed.h5:' "$d/slurm.out" || true)
	[ "$n" = 1 ] || fail "job $id: $n summaries from $tasks tasks, 1 expected (one MPI job)"
	# relax says "on 2 ranks x 1 thread", or "on 2 threads" for one rank
	ranks=""
	[ "$tasks" = 1 ] || ranks="$tasks ranks x "
	grep -q "on $ranks$threads thread" "$d/slurm.out" ||
		fail "job $id: not on $ranks$threads thread(s)"
	/usr/bin/python3 "$root/tools/compare_outputs.py" "$tmp/serial.h5" "$d/relaxed.h5" ||
		fail "job $id ($tasks tasks x $threads CPUs): relaxed.h5 is not the serial build's"
done
ok=1
echo "test-slurm: ok"
