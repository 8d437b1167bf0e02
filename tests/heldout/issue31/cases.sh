# The cases (sourced by run.sh). Each case_X runs in its own directory and namespaces and
# writes its verdict line(s) with `result`. Truth is in CASES.md.

LAB_URL='udpm://239.255.76.67:7667?ttl=1'

# lab_services CASE HOST HOSTNAME [fitter args...]: spindown-fitter and spindown-logger (logs/)
lab_services() {
  local c=$1 h=$2 hn=$3; shift 3
  mkdir -p logs
  bg "$c" "$h" "$hn" fitter.out fitter.err "$BIN/spindown-fitter" --lcm-url "$LAB_URL" -v "$@"; PID_F=$LASTPID
  bg "$c" "$h" "$hn" logger.out logger.err "$BIN/spindown-logger" --lcm-url "$LAB_URL" --dir logs; PID_L=$LASTPID
  sleep 0.6
}

# ---------------------------------------------------------------- replug
# bench-1 (an Uno, lab sketch): cable pulled at bench 80 s (run 2 coasting) for 5 s, udev
# restarts its bridge on the new port (the board boots when it is back); `systemctl restart`
# of its bridge at bench 95 s (same coast) and at 200 s after a long idle: the board resets as
# its port opens, so the new bridge reads the new clock from ~0 and nothing from before.
# bench-2 (a board that does not reset when its port opens): its bridge restarted at bench 50 s
# (idle) and 90 s (mid-coast): seq restarts at 0, the device clock goes on, no line lost.
case_replug() {
  local C=rp S=10
  H31_NET=11
  make_switch $C && add_host $C srv 1 && add_host $C bp 2 || { runner_fail replug-uno "topology"; return; }
  lab_services $C srv lab-pc
  bench $C bp bench-pc bench-1 --runs 5 --idle 40 --speed $S --seed 311 --wait-reader 10 \
        --unplug-at 80 --unplug-for 5 --reset-at 95 --reset-at 200 --linger 1
  bench $C bp bench-pc bench-2 --runs 5 --idle 40 --speed $S --seed 312 --wait-reader 10 \
        --coulomb 1.6e-4 --viscous 1.2e-7 --linger 1
  bridge_t0 $C bp bench-pc bench-1 "$(cat bench-1.tty)" "$LAB_URL" a; local b1=$LASTPID; local t1=$T0
  bridge_t0 $C bp bench-pc bench-2 "$(cat bench-2.tty)" "$LAB_URL" a; local b2=$LASTPID; local t2=$T0
  at() { awk -v s=$S -v b="$1" 'BEGIN{print b/s}'; }   # bench seconds -> wall seconds
  # bench-2's bridge restarted at bench 50 s (idle)
  sleep_until $t2 $(at 50); stop $b2
  bridge $C bp bench-pc bench-2 "$(cat bench-2.tty)" "$LAB_URL" b; b2=$LASTPID
  # bench-1 unplugged at 80 s: its bridge loses the port; udev/systemd restart it on the new one
  sleep_until $t1 $(at 78)
  wait_for "grep -q disconnected bench-1.a.br.err" 3 || echo "bench-1 bridge a saw no disconnect" >&2
  stop $b1
  if wait_for "[ \$(wc -l < bench-1.vb.out) -ge 2 ]" 3; then
    bridge $C bp bench-pc bench-1 "$(sed -n 2p bench-1.vb.out)" "$LAB_URL" b; b1=$LASTPID
  else
    runner_fail replug-uno "bench-1 printed no new port after its unplug"
  fi
  local dev1; dev1=$(sed -n 2p bench-1.vb.out)
  # bench-2's bridge restarted at bench 90 s (run 2 coasting)
  sleep_until $t2 $(at 90); stop $b2
  bridge $C bp bench-pc bench-2 "$(cat bench-2.tty)" "$LAB_URL" c; b2=$LASTPID
  # systemctl restart of bench-1's bridge: the board resets (bench 95 s) as the port opens
  sleep_until $t1 $(at 93); stop $b1
  sleep_until $t1 $(at 97); $PY "$HERE/tools.py" ptyflush "$dev1"
  bridge $C bp bench-pc bench-1 "$dev1" "$LAB_URL" c; b1=$LASTPID
  # and again after a long idle (bench 200 s)
  sleep_until $t1 $(at 198); stop $b1
  sleep_until $t1 $(at 202); $PY "$HERE/tools.py" ptyflush "$dev1"
  bridge $C bp bench-pc bench-1 "$dev1" "$LAB_URL" d; b1=$LASTPID
  wait_exit $PID_VB_bench_1 40; wait_exit $PID_VB_bench_2 10
  sleep 2
  stop $PID_F; stop $PID_L; stop $b1; stop $b2
  local log; log=$(ls logs/*.lcm)
  result "$(judge_fits replug-uno "$log" bench-1=bench-1.truth.json=1,3,4,5=2)"
  result "$(judge_fits replug-no-reset "$log" bench-2=bench-2.truth.json=1,3,4,5=2)"
}

# truthval FILE EXPR: a number from a truth JSON (EXPR in Python over d)
truthval() { $PY -c "import json,sys; d=json.load(open(sys.argv[1])); print($2)" "$1"; }

# ---------------------------------------------------------------- outage across a cut
# bench-1 on its own PC (lead-in "supply": the pin reads the supply before the cut; a long
# coast, 49.4 s) loses its uplink (its port on the lab switch goes down) three times:
# (a) run 1 mid-coast, from 8 s to 34 s after the cut; (b) from 4 s before run 2's cut to 22 s
# after it: the cut happens in the outage; (c) run 3 from 10 s after the cut to 3.4 s before
# its stop. Run 4 is clean. bench-2 on another PC is never cut off. Speed 10; fitter --silent 2.
case_outage_cut() {
  local C=oc S=10
  H31_NET=12
  make_switch $C && add_host $C srv 1 && add_host $C bp1 2 && add_host $C bp2 3 || { runner_fail outage-cut "topology"; return; }
  lab_services $C srv lab-pc --silent 2
  bench $C bp1 bench-pc-1 bench-1 --runs 4 --idle 5 --speed $S --seed 321 --wait-reader 10 \
        --lead-in supply --lead-in-s 12 --coulomb 6e-5 --viscous 1.2e-7 --linger 1
  bench $C bp2 bench-pc-2 bench-2 --runs 5 --idle 5 --speed $S --seed 322 --wait-reader 10 --linger 1
  bridge_t0 $C bp1 bench-pc-1 bench-1 "$(cat bench-1.tty)" "$LAB_URL" a; local b1=$LASTPID; local t1=$T0
  bridge $C bp2 bench-pc-2 bench-2 "$(cat bench-2.tty)" "$LAB_URL" a; local b2=$LASTPID
  local sw; sw=$(ns_name $C sw)   # the lab switch: bench-pc-1's port is p2
  local o k c
  for o in "0 8 34" "1 -4 22" "2 10 46"; do
    set -- $o
    c=$(truthval bench-1.truth.json "d['runs'][$1]['cut_bench_s']")
    sleep_until $t1 $(awk -v c=$c -v a=$2 -v s=$S 'BEGIN{print (c+a)/s}')
    ip -n $sw link set p2 down; echo "outage from $(now) (bench $(awk -v c=$c -v a=$2 'BEGIN{print c+a}'))"
    sleep_until $t1 $(awk -v c=$c -v a=$3 -v s=$S 'BEGIN{print (c+a)/s}')
    ip -n $sw link set p2 up; echo "outage to $(now) (bench $(awk -v c=$c -v a=$3 'BEGIN{print c+a}'))"
  done
  wait_exit $PID_VB_bench_1 40; wait_exit $PID_VB_bench_2 10
  sleep 2
  stop $PID_F; stop $PID_L; stop $b1; stop $b2
  local log; log=$(ls logs/*.lcm)
  # runs 1 and 3: cut seen (whole across the gap, or closed at the gap); run 2: cut not seen
  result "$(judge_fits outage-cut "$log" bench-1=bench-1.truth.json=4=1,2,3 bench-2=bench-2.truth.json=1,2,3,4,5=)"
}

# ---------------------------------------------------------------- frozen fitter
# The fitter is frozen (SIGSTOP) for 5.5 s while bench-2's run 1 stops, bench-1's run 1 is cut
# and bench-2's run 2 is cut, and bench-3 coasts through it; nothing is lost (the kernel queues every datagram for it: checked
# from the fitter's socket drops in /proc/net/udp). Fitter --silent 2. Speed 4.
case_frozen() {
  local C=fz S=4
  H31_NET=13
  make_switch $C && add_host $C srv 1 && add_host $C bp 2 || { runner_fail frozen-fitter "topology"; return; }
  lab_services $C srv lab-pc --silent 2
  bench $C bp bench-pc bench-1 --runs 1 --speed $S --seed 331 --wait-reader 10 --lead-in-s 34 \
        --coulomb 9e-5 --viscous 1.6e-7 --linger 1
  bench $C bp bench-pc bench-2 --runs 2 --idle 5 --speed $S --seed 332 --wait-reader 10 --linger 1
  bench $C bp bench-pc bench-3 --runs 1 --speed $S --seed 333 --wait-reader 10 --lead-in-s 16 \
        --coulomb 7e-5 --viscous 1.4e-7 --linger 1
  bridge_t0 $C bp bench-pc bench-2 "$(cat bench-2.tty)" "$LAB_URL" a; local b2=$LASTPID; local t2=$T0
  bridge_t0 $C bp bench-pc bench-1 "$(cat bench-1.tty)" "$LAB_URL" a; local b1=$LASTPID; local t1=$T0
  bridge $C bp bench-pc bench-3 "$(cat bench-3.tty)" "$LAB_URL" a; local b3=$LASTPID
  local s2 c1 c2
  s2=$(truthval bench-2.truth.json "d['runs'][0]['cut_bench_s']+d['runs'][0]['t_stop_s']")
  c1=$(truthval bench-1.truth.json "d['runs'][0]['cut_bench_s']")
  c2=$(truthval bench-2.truth.json "d['runs'][1]['cut_bench_s']")
  echo "bench-2 stop 1 at wall $(awk -v a=$s2 -v s=$S 'BEGIN{print a/s}'), bench-1 cut at $(awk -v a=$c1 -v s=$S -v d=$(awk -v x=$t1 -v y=$t2 'BEGIN{print x-y}') 'BEGIN{print a/s+d}'), bench-2 cut 2 at $(awk -v a=$c2 -v s=$S 'BEGIN{print a/s}')"
  sleep_until $t2 6.5
  kill -STOP $PID_F; echo "frozen at $(now)"
  local ns; ns=$(ns_name $C srv)
  sleep_until $t2 11.9
  # the fitter's own sockets' kernel drops (the 'drops' column of /proc/net/udp for its inodes)
  local inodes drops
  inodes=$(ls -l /proc/$PID_F/fd 2>/dev/null | sed -n 's/.*socket:\[\([0-9]*\)\].*/\1/p' | tr '\n' ' ')
  drops=$(ip netns exec $ns cat /proc/net/udp | awk -v l=" $inodes " 'NR>1 && index(l, " " $10 " ") {d+=$13} END{print d+0}')
  echo "fitter socket drops while frozen: $drops (inodes $inodes)"
  sleep_until $t2 12
  kill -CONT $PID_F; echo "thawed at $(now)"
  wait_exit $PID_VB_bench_1 40; wait_exit $PID_VB_bench_2 20; wait_exit $PID_VB_bench_3 20
  sleep 2
  drops=$(ip netns exec $ns cat /proc/net/udp | awk -v l=" $inodes " 'NR>1 && index(l, " " $10 " ") {d+=$13} END{print d+0}')
  stop $PID_F; stop $PID_L; stop $b1; stop $b2; stop $b3
  local log; log=$(ls logs/*.lcm)
  if [ "$drops" != 0 ]; then
    result "FAIL frozen-fitter: runner premise broken: the kernel dropped $drops datagrams on the frozen fitter's socket (the truth assumes none; raise net.core.rmem_max)"
    return
  fi
  # nothing was lost: every run is whole, live (the frozen fitter) and in refit
  result "$(judge_fits frozen-fitter "$log" bench-1=bench-1.truth.json=1= bench-2=bench-2.truth.json=1,2= bench-3=bench-3.truth.json=1= "extra=(fitter socket drops: 0)")"
}

# ---------------------------------------------------------------- rotated session
# The logger rotates by size (30 kB: several files a second, named …-HHMMSS.lcm, …-HHMMSS.1.lcm,
# …), so runs straddle file boundaries. `spindown refit logs/*.lcm` (the shell's order, which
# puts …-HHMMSS.1.lcm before …-HHMMSS.lcm) and the files in reverse order must both be one
# session: the live fitter's runs and numbers, and the benches' truth.
case_rotated() {
  local C=ro S=10
  H31_NET=14
  make_switch $C && add_host $C srv 1 && add_host $C bp 2 || { runner_fail refit-rotated "topology"; return; }
  mkdir -p logs
  bg $C srv lab-pc fitter.out fitter.err "$BIN/spindown-fitter" --lcm-url "$LAB_URL" -v; PID_F=$LASTPID
  bg $C srv lab-pc logger.out logger.err "$BIN/spindown-logger" --lcm-url "$LAB_URL" --dir logs --rotate-size 0.03; PID_L=$LASTPID
  sleep 0.6
  bench $C bp bench-pc bench-1 --runs 3 --idle 3 --speed $S --seed 341 --wait-reader 10 --linger 1
  bench $C bp bench-pc bench-2 --runs 3 --idle 3 --speed $S --seed 342 --wait-reader 10 --lead-in-s 9 \
        --coulomb 1.5e-4 --viscous 2.2e-7 --linger 1
  bridge $C bp bench-pc bench-1 "$(cat bench-1.tty)" "$LAB_URL" a; local b1=$LASTPID
  bridge $C bp bench-pc bench-2 "$(cat bench-2.tty)" "$LAB_URL" a; local b2=$LASTPID
  wait_exit $PID_VB_bench_1 40; wait_exit $PID_VB_bench_2 20
  sleep 2
  stop $PID_F; stop $PID_L; stop $b1; stop $b2
  local files rev n
  files=$(ls logs/*.lcm)                 # the shell's order
  rev=$(ls logs/*.lcm | sort -r)
  n=$(echo $files | wc -w)
  timeout 60 "$BIN/spindown" refit --live --json $files > live.json 2> live.err
  timeout 60 "$BIN/spindown" refit --json $files > refit-glob.json 2> refit-glob.err
  timeout 60 "$BIN/spindown" refit --json $rev > refit-rev.json 2> refit-rev.err
  timeout 60 "$BIN/spindown" refit --compare $files > compare.txt 2> compare.err; local crc=$?
  local v1 v2
  v1=$($PY "$HERE/judge.py" fits refit-rotated live.json refit-glob.json \
        bench-1=bench-1.truth.json=1,2,3= bench-2=bench-2.truth.json=1,2,3=)
  v2=$($PY "$HERE/judge.py" equal refit-rotated live.json "refit(shell order)=refit-glob.json" "refit(reverse order)=refit-rev.json")
  local rv; rv=$($PY "$HERE/judge.py" fits refit-rotated - refit-rev.json \
        bench-1=bench-1.truth.json=1,2,3= bench-2=bench-2.truth.json=1,2,3=)
  if [[ $v1 == PASS* && $v2 == PASS* && $rv == PASS* && $crc == 0 ]]; then
    result "PASS refit-rotated: $n files; ${v1#PASS refit-rotated: }; ${v2#PASS refit-rotated: }; refit --compare exit 0"
  else
    local why=""
    [[ $v1 == PASS* ]] || why="$why ${v1#FAIL refit-rotated: };"
    [[ $rv == PASS* ]] || why="$why reverse order: ${rv#FAIL refit-rotated: };"
    [[ $v2 == PASS* ]] || why="$why ${v2#FAIL refit-rotated: };"
    [ $crc = 0 ] || why="$why refit --compare exit $crc (want 0: identical);"
    result "FAIL refit-rotated: $n files:$why"
  fi
}

# ---------------------------------------------------------------- SIGTERM mid-coast
# `systemctl stop spindown-fitter` (SIGTERM) while bench-1 and bench-2 both coast (cut 16.5 s
# and 9.5 s before it); a `spindown watch --plain` listens across it; the fitter is started
# again while bench-2 still coasts. Speed 5.
case_sigterm() {
  local C=st S=5
  H31_NET=15
  make_switch $C && add_host $C srv 1 && add_host $C bp 2 && add_host $C ws 3 || { runner_fail sigterm-open-runs "topology"; return; }
  lab_services $C srv lab-pc
  bench $C bp bench-pc bench-1 --runs 3 --idle 5 --speed $S --seed 351 --wait-reader 10 --linger 1
  bench $C bp bench-pc bench-2 --runs 2 --idle 5 --speed $S --seed 352 --wait-reader 10 --lead-in-s 10 \
        --coulomb 8e-5 --viscous 1.822e-7 --linger 1
  bg $C ws teacher-pc watch.out watch.err "$BIN/spindown" watch --plain --interval 0.5 --duration 60 --lcm-url "$LAB_URL"
  local pw=$LASTPID
  bridge_t0 $C bp bench-pc bench-1 "$(cat bench-1.tty)" "$LAB_URL" a; local b1=$LASTPID; local t1=$T0
  bridge $C bp bench-pc bench-2 "$(cat bench-2.tty)" "$LAB_URL" a; local b2=$LASTPID
  sleep_until $t1 $(awk -v s=$S 'BEGIN{print 20/s}')
  local tterm; tterm=$(date +%s%N)
  kill -TERM $PID_F
  local rc=timeout
  if wait_exit $PID_F 5; then wait $PID_F; rc=$?; else kill -KILL $PID_F; fi
  local texit; texit=$(date +%s%N)
  echo "SIGTERM at $tterm, exit $rc at $texit"
  # the teacher's watch is closed 2 s after the fitter stopped (its last table: what it shows then)
  sleep 2; kill -TERM $pw; wait_exit $pw 5; wait $pw 2>/dev/null
  # started again while bench-2 still coasts (bench 32.5 s: bench-1 stopped at 30.7, bench-2 coasts to ~46)
  sleep_until $t1 $(awk -v s=$S 'BEGIN{print 32.5/s}')
  local trestart; trestart=$(date +%s%N)
  bg $C srv lab-pc fitter2.out fitter2.err "$BIN/spindown-fitter" --lcm-url "$LAB_URL" -v; local f2=$LASTPID
  wait_exit $PID_VB_bench_1 40; wait_exit $PID_VB_bench_2 20
  sleep 2
  stop $f2; stop $PID_L; stop $b1; stop $b2
  local log; log=$(ls logs/*.lcm)
  timeout 60 "$BIN/spindown" export "$log" --mcap session.mcap > export.out 2> export.err
  local c1 c2
  c1=$(truthval bench-1.truth.json "d['runs'][0]['cut_device_us']/1e6")
  c2=$(truthval bench-2.truth.json "d['runs'][0]['cut_device_us']/1e6")
  local va vf
  va=$($PY "$HERE/judge.py" abandoned sigterm-open-runs session.mcap "$tterm" "$trestart" "bench-1=$c1" "bench-2=$c2" \
        "exit=$rc" "watch=watch.out")
  vf=$(judge_fits sigterm-open-runs "$log" bench-1=bench-1.truth.json=2,3=1 bench-2=bench-2.truth.json=2=1)
  if [[ $va == PASS* && $vf == PASS* ]]; then
    result "PASS sigterm-open-runs: ${va#PASS sigterm-open-runs: }; ${vf#PASS sigterm-open-runs: }"
  else
    local why=""
    [[ $va == PASS* ]] || why="$why ${va#FAIL sigterm-open-runs: };"
    [[ $vf == PASS* ]] || why="$why ${vf#FAIL sigterm-open-runs: };"
    result "FAIL sigterm-open-runs:$why"
  fi
}

# ---------------------------------------------------------------- replay of yesterday's log
# Yesterday bench-1 had a worn motor (c_c 2.4e-4, c_v 2.6e-7) and ran 8 runs; its log is kept.
# Today (a good motor, 6 runs) a student's laptop on the lab switch plays yesterday's log from
# run 7 on (its SAMPLE and CONFIG only) onto the lab's URL with lcm-logplayer, at today's pace,
# while today's bench-1 idles and then coasts (today bench 34 s to ~81 s).
case_replay() {
  local C=rp2 S=10
  H31_NET=16
  make_switch $C && add_host $C srv 1 && add_host $C bp 2 && add_host $C lap 3 || { runner_fail replay-yesterday "topology"; return; }
  # --- yesterday
  mkdir -p yday && cd yday
  mkdir -p logs
  bg $C srv lab-pc logger.out logger.err "$BIN/spindown-logger" --lcm-url "$LAB_URL" --dir logs; local ly=$LASTPID
  sleep 0.5
  bench $C bp bench-pc bench-1 --runs 8 --idle 4 --speed 60 --seed 361 --wait-reader 10 \
        --coulomb 2.4e-4 --viscous 2.6e-7 --linger 0.5
  bridge $C bp bench-pc bench-1 "$(cat bench-1.tty)" "$LAB_URL" y; local by=$LASTPID
  wait_exit $PID_VB_bench_1 20; sleep 1
  stop $ly; stop $by
  local ylog; ylog=$(ls logs/*.lcm)
  timeout 60 "$BIN/spindown" export "$ylog" --csv -o y.csv --no-fits > /dev/null 2> export.err
  local c7 th n
  c7=$(truthval bench-1.truth.json "d['runs'][6]['cut_device_us']/1e6")
  th=$($PY "$HERE/tools.py" hosttime y.csv bench-1 "$(awk -v c=$c7 'BEGIN{print c-5}')")
  n=$($PY "$HERE/tools.py" trimlog "$ylog" ../replay.lcm "$th" 'SPINDOWN\.bench-1\.(SAMPLE|CONFIG)')
  cd ..
  cp yday/bench-1.truth.json yesterday.truth.json
  echo "yesterday: run 7 cut at device $c7 s; replay log of $n events from host time $th"
  # --- today
  lab_services $C srv lab-pc
  bench $C bp bench-pc bench-1 --runs 6 --idle 5 --speed $S --seed 362 --wait-reader 10 --linger 1
  bridge_t0 $C bp bench-pc bench-1 "$(cat bench-1.tty)" "$LAB_URL" a; local b1=$LASTPID; local t1=$T0
  sleep_until $t1 $(awk -v s=$S 'BEGIN{print 34/s}')
  echo "replay starts at $(now)"
  bg $C lap student-laptop replay.out replay.err lcm-logplayer -s 0.25 -l "$LAB_URL" replay.lcm; local pr=$LASTPID
  wait_exit $pr 15 || { echo "replay still running"; stop $pr; }
  echo "replay ended at $(now) (bench $(awk -v a=$t1 -v n=$(now) -v s=$S 'BEGIN{print (n-a)*s}'))"
  wait_exit $PID_VB_bench_1 40
  sleep 2
  grep -v ': stopped:' fitter.err > fitter.live.err   # what it said while running (not its exit summary)
  stop $PID_F; stop $PID_L; stop $b1
  local log; log=$(ls logs/*.lcm)
  local vf named
  vf=$(judge_fits replay-yesterday "$log" bench-1=bench-1.truth.json=1,4,5,6=2,3 other:yesterday=yesterday.truth.json)
  # the replay named: a fitter line about bench-1 naming a second source, a replay or a forgery
  # (loose, case-insensitive keywords)
  named=$(grep -i 'bench-1' fitter.live.err | grep -iE 'two sources|second source|another source|other source|replay|forg|spoof|imperson|impostor' | head -1)
  if [[ $vf == PASS* && -n $named ]]; then
    result "PASS replay-yesterday: ${vf#PASS replay-yesterday: }; named: $(echo "$named" | cut -c1-160)"
  else
    local why=""
    [[ $vf == PASS* ]] || why="$why ${vf#FAIL replay-yesterday: };"
    [ -n "$named" ] || why="$why the fitter's stderr never names the replayed second source on bench-1 ($(grep -ciE 'duplicate|repeat' fitter.live.err) lines about duplicates/repeats);"
    result "FAIL replay-yesterday:$why"
  fi
}

# ---------------------------------------------------------------- two labs, one PC serves both
# Lab A (group 239.255.76.67) and lab B (group 239.255.76.68) both on port 7667 and ttl=1, each
# with benches bench-1 and bench-2 (different motors), on one switch. One server PC runs lab A's
# fitter (--instance lab-a, lab A's URL) and lab B's (--instance lab-b, lab B's URL). What each
# lab's network carries is recorded by a logger on that lab's bench PC (which joins only its
# lab's group); `spindown doctor` runs on the server with lab A's URL while both labs run.
case_twolabs_onepc() {
  local C=tl S=10
  local UA='udpm://239.255.76.67:7667?ttl=1' UB='udpm://239.255.76.68:7667?ttl=1'
  H31_NET=17
  make_switch $C && add_host $C srv 1 && add_host $C la 2 && add_host $C lb 3 || { runner_fail twolabs-one-pc "topology"; return; }
  mkdir -p logsA logsB
  bg $C srv shared-pc fitterA.out fitterA.err "$BIN/spindown-fitter" --lcm-url "$UA" --instance lab-a -v; local fa=$LASTPID
  bg $C srv shared-pc fitterB.out fitterB.err "$BIN/spindown-fitter" --lcm-url "$UB" --instance lab-b -v; local fb=$LASTPID
  bg $C la lab-a-bench-pc loggerA.out loggerA.err "$BIN/spindown-logger" --lcm-url "$UA" --dir logsA; local la=$LASTPID
  bg $C lb lab-b-bench-pc loggerB.out loggerB.err "$BIN/spindown-logger" --lcm-url "$UB" --dir logsB; local lb=$LASTPID
  sleep 0.6
  mkdir -p A B
  bench $C la lab-a-bench-pc A/bench-1 --runs 2 --idle 5 --speed $S --seed 371 --wait-reader 10 --linger 1
  bench $C la lab-a-bench-pc A/bench-2 --runs 2 --idle 5 --speed $S --seed 372 --wait-reader 10 \
        --coulomb 1.3e-4 --viscous 1.5e-7 --linger 1
  bench $C lb lab-b-bench-pc B/bench-1 --runs 2 --idle 5 --speed $S --seed 373 --wait-reader 10 --lead-in-s 7 \
        --coulomb 2.2e-4 --viscous 2.8e-7 --linger 1
  bench $C lb lab-b-bench-pc B/bench-2 --runs 2 --idle 5 --speed $S --seed 374 --wait-reader 10 --lead-in-s 9 \
        --coulomb 1.8e-4 --viscous 2.0e-7 --linger 1
  local br=()
  bg $C la lab-a-bench-pc A/b1.br.out A/b1.br.err "$BIN/spindown-bridge" --device "$(cat A/bench-1.tty)" --bench bench-1 --lcm-url "$UA"; br+=($LASTPID)
  bg $C la lab-a-bench-pc A/b2.br.out A/b2.br.err "$BIN/spindown-bridge" --device "$(cat A/bench-2.tty)" --bench bench-2 --lcm-url "$UA"; br+=($LASTPID)
  bg $C lb lab-b-bench-pc B/b1.br.out B/b1.br.err "$BIN/spindown-bridge" --device "$(cat B/bench-1.tty)" --bench bench-1 --lcm-url "$UB"; br+=($LASTPID)
  bg $C lb lab-b-bench-pc B/b2.br.out B/b2.br.err "$BIN/spindown-bridge" --device "$(cat B/bench-2.tty)" --bench bench-2 --lcm-url "$UB"; br+=($LASTPID)
  sleep 2
  ( on $C srv shared-pc timeout 20 "$BIN/spindown" doctor --json --lcm-url "$UA" --listen 3 --timeout 2 > doctor.json 2> doctor.err )
  local p
  for p in $PID_VB_A_bench_1 $PID_VB_A_bench_2 $PID_VB_B_bench_1 $PID_VB_B_bench_2; do wait_exit $p 30; done
  sleep 2
  grep -v ': stopped:' fitterA.err > fitterA.live.err; grep -v ': stopped:' fitterB.err > fitterB.live.err
  for p in $fa $fb $la $lb "${br[@]}"; do stop $p; done
  local logA logB; logA=$(ls logsA/*.lcm); logB=$(ls logsB/*.lcm)
  local vA vB named
  vA=$(judge_fits labA "$logA" bench-1=A/bench-1.truth.json==1,2 bench-2=A/bench-2.truth.json==1,2 \
        other:lab-B-bench-1=B/bench-1.truth.json other:lab-B-bench-2=B/bench-2.truth.json)
  vB=$(judge_fits labB "$logB" bench-1=B/bench-1.truth.json==1,2 bench-2=B/bench-2.truth.json==1,2 \
        other:lab-A-bench-1=A/bench-1.truth.json other:lab-A-bench-2=A/bench-2.truth.json)
  # named: lab A's fitter names lab B's bench PC (or lab B's names lab A's), or either says
  # "two sources"/"second|another|other source"/"another|other lab" (loose, case-insensitive)
  named=$( { grep -i 'lab-b-bench-pc' fitterA.live.err; grep -i 'lab-a-bench-pc' fitterB.live.err;
             cat fitterA.live.err fitterB.live.err | grep -iE 'two sources|second source|another source|other source|another lab|other lab'; } | head -1)
  if [[ $vA == PASS* && $vB == PASS* && -n $named ]]; then
    result "PASS twolabs-one-pc: lab A's network: ${vA#PASS labA: }; lab B's: ${vB#PASS labB: }; named: $(echo "$named" | cut -c1-160)"
  else
    local why=""
    [[ $vA == PASS* ]] || why="$why lab A's network (fitter lab-a): ${vA#FAIL labA: };"
    [[ $vB == PASS* ]] || why="$why lab B's network (fitter lab-b): ${vB#FAIL labB: };"
    [ -n "$named" ] || why="$why neither fitter's stderr names the other lab's bench PC or a second source on its bench channels;"
    result "FAIL twolabs-one-pc:$why"
  fi
  # doctor on the PC that serves both labs, with lab A's URL: the other lab's traffic is named
  local vd
  vd=$($PY "$HERE/judge.py" doctor twolabs-doctor doctor.json lab-b-bench-pc 239.255.76.68)
  result "$vd"
}

# ---------------------------------------------------------------- two labs, one fitter name
# Two labs on one network (same group, port, ttl=1), with different bench names (lab A: a-1,
# lab B: b-1), each with its own lab PC running spindown-fitter with the default instance name.
# A teacher's PC runs `spindown watch --once` while both run.
case_twolabs_instance() {
  local C=ti S=10
  H31_NET=18
  make_switch $C && add_host $C pa 1 && add_host $C pb 2 && add_host $C ba 3 && add_host $C bb 4 && add_host $C ws 5 \
    || { runner_fail twolabs-same-instance "topology"; return; }
  mkdir -p logs
  bg $C pa lab-a-pc fitterA.out fitterA.err "$BIN/spindown-fitter" --lcm-url "$LAB_URL" -v; local fa=$LASTPID
  bg $C pb lab-b-pc fitterB.out fitterB.err "$BIN/spindown-fitter" --lcm-url "$LAB_URL" -v; local fb=$LASTPID
  bg $C pa lab-a-pc logger.out logger.err "$BIN/spindown-logger" --lcm-url "$LAB_URL" --dir logs; local lg=$LASTPID
  sleep 0.6
  bench $C ba lab-a-bench-pc a-1 --runs 2 --idle 5 --speed $S --seed 381 --wait-reader 10 --linger 1
  bench $C bb lab-b-bench-pc b-1 --runs 2 --idle 5 --speed $S --seed 382 --wait-reader 10 --lead-in-s 6 \
        --coulomb 2.2e-4 --viscous 2.8e-7 --linger 1
  bridge $C ba lab-a-bench-pc a-1 "$(cat a-1.tty)" "$LAB_URL" a; local b1=$LASTPID
  bridge $C bb lab-b-bench-pc b-1 "$(cat b-1.tty)" "$LAB_URL" a; local b2=$LASTPID
  sleep 2
  ( on $C ws teacher-pc timeout 15 "$BIN/spindown" watch --once --duration 3 --lcm-url "$LAB_URL" > watch.txt 2> watch.err )
  wait_exit $PID_VB_a_1 40; wait_exit $PID_VB_b_1 20
  sleep 2
  grep -v ': stopped:' fitterA.err > fitterA.live.err; grep -v ': stopped:' fitterB.err > fitterB.live.err
  stop $fa; stop $fb; stop $lg; stop $b1; stop $b2
  local log; log=$(ls logs/*.lcm)
  local vf vw
  vf=$(judge_fits twolabs-same-instance "$log" a-1=a-1.truth.json=1,2= b-1=b-1.truth.json=1,2= max_per_run=2)
  vw=$($PY "$HERE/judge.py" collision twolabs-same-instance watch.txt fitterA.live.err fitterB.live.err lab-a-pc lab-b-pc)
  if [[ $vf == PASS* && $vw == PASS* ]]; then
    result "PASS twolabs-same-instance: ${vf#PASS twolabs-same-instance: }; ${vw#PASS twolabs-same-instance: }"
  else
    local why=""
    [[ $vf == PASS* ]] || why="$why ${vf#FAIL twolabs-same-instance: };"
    [[ $vw == PASS* ]] || why="$why ${vw#FAIL twolabs-same-instance: };"
    result "FAIL twolabs-same-instance:$why"
  fi
}

# ---------------------------------------------------------------- the fitter's route gone
# The lab PC's multicast route (224.0.0.0/4 dev eth0, added by hand as lab-setup.md step 6 says)
# is removed while bench-1's run 1 coasts (a network manager re-applying the connection without
# it) and added back 3.5 s later; run 1 stops and is fitted meanwhile. The logger is on another
# PC (the archive). Speed 10.
case_route_gone() {
  local C=rg S=10
  H31_NET=19
  make_switch $C && add_host $C srv 1 && add_host $C ar 2 && add_host $C bp 3 || { runner_fail route-gone "topology"; return; }
  mkdir -p logs
  bg $C srv lab-pc fitter.out fitter.err "$BIN/spindown-fitter" --lcm-url "$LAB_URL" -v; PID_F=$LASTPID
  bg $C ar archive-pc logger.out logger.err "$BIN/spindown-logger" --lcm-url "$LAB_URL" --dir logs; PID_L=$LASTPID
  sleep 0.6
  bench $C bp bench-pc bench-1 --runs 3 --idle 5 --speed $S --seed 391 --wait-reader 10 --linger 1
  bridge_t0 $C bp bench-pc bench-1 "$(cat bench-1.tty)" "$LAB_URL" a; local b1=$LASTPID; local t1=$T0
  local ns; ns=$(ns_name $C srv)
  sleep_until $t1 1.5
  ip -n $ns route del 224.0.0.0/4 dev eth0; echo "route removed at $(now)"
  sleep_until $t1 5.0
  ip -n $ns route add 224.0.0.0/4 dev eth0; echo "route back at $(now)"
  sleep 2; cp fitter.err fitter.noroute.err   # what it said by 2 s after the route came back
  wait_exit $PID_VB_bench_1 40
  sleep 2
  local alive=yes; kill -0 $PID_F 2>/dev/null || alive=no
  stop $PID_F; stop $PID_L; stop $b1
  local log; log=$(ls logs/*.lcm)
  local vf said prem
  vf=$(judge_fits route-gone "$log" bench-1=bench-1.truth.json=2,3=1)
  said=$(grep -iE 'publish|send|sent' fitter.noroute.err | grep -v ': stopped:' | grep -vE '\b0 (publish|send)' | grep -iE 'fail|error|cannot|could not|unreachable|no route|not sent|lost|unable' | head -1)
  prem=$($PY -c '
import json,sys
d=json.load(open("route-gone.live.json"))
cuts=[r["t_cut_s"] for f in d["files"] for r in f["runs"]]
print("run-1 FIT reached the archive" if any(c is not None and abs(c-3.5)<0.1 for c in cuts) else "run-1 FIT never reached the archive")')
  if [[ $vf == PASS* && -n $said && $alive == yes ]]; then
    result "PASS route-gone: said: $(echo "$said" | cut -c1-160); ${vf#PASS route-gone: } ($prem)"
  else
    local why=""
    [ -n "$said" ] || why="$why the fitter said nothing on stderr about FITs it could not publish ($prem);"
    [ $alive = yes ] || why="$why the fitter died;"
    [[ $vf == PASS* ]] || why="$why ${vf#FAIL route-gone: };"
    result "FAIL route-gone:$why"
  fi
}
