#!/bin/bash
# case.sh NAME BIN SCR: runs one issue-42 held-out case (the scenario), then judges it.
# Writes $SCR/verdict ("PASS" or "FAIL: why" or "HARNESS: why"). Bounded by run.sh's timeout.
NAME=$1 BIN=$2 SCR=$3
export BIN SCR
source "$(dirname "$0")/lib.sh"
echo "HARNESS: the scenario did not finish" > "$SCR/verdict"

now_us() { date +%s%6N; }
# at T_ABS: sleep until epoch seconds T_ABS (fractional), bounded to 120 s
sleep_until() { local d; d=$(python3 -c "import time; print(max(0.0, min(120.0, $1 - time.time())))"); sleep "$d"; }
t_now() { date +%s.%N; }

finish() {    # stop what the scenario started, in the order a lab would (bridges, fitter, loggers)
    local t
    for t in "$@"; do [ -e "$SCR/$t.pid" ] && stop "$t"; done
}

scenario_dup_reorder() {
    ns_two lab pc1
    net '{"dup_p":0.25,"dup_extra_ms":[0,80],"reorder_p":0.4,"reorder_ms":60}'
    logger lab lablog "$URL0" lablogs
    logger pc1 witness "$URL0" witlogs
    fitter lab fitter "$URL0"
    vbench pc1 vb1 11 --runs 2 "${VB_COMMON[@]}" --coulomb 4e-4
    vbench pc1 vb2 12 --runs 2 "${VB_COMMON[@]}" --coulomb 3e-4
    sleep 0.5
    bridge pc1 br1 bench-1 vb1 "$URL0"
    bridge pc1 br2 bench-2 vb2 "$URL0"
    wait_bench_done vb1 70; wait_bench_done vb2 30
    sleep 3
    finish br1 br2 fitter lablog witness relay
}

scenario_late_block() {
    ns_two lab pc1
    logger lab lablog "$URL0" lablogs
    logger pc1 witness "$URL0" witlogs
    fitter lab fitter "$URL0"
    vbench pc1 vb1 21 --runs 2 "${VB_COMMON[@]}" --coulomb 3e-4
    sleep 0.5
    local t0; t0=$(t_now)
    bridge pc1 br1 bench-1 vb1 "$URL0"
    sleep_until "$t0 + 2.5 + 3"          # 3 s into run 1's coast (cut at device 2.5 s)
    net '{"delay_ms":1500}'
    sleep 1.5
    net '{}'
    wait_bench_done vb1 70
    sleep 3
    finish br1 fitter lablog witness relay
}

scenario_burst_loss() {
    ns_two lab pc1
    net '{"ge_p":0.02,"ge_r":0.2,"straggle_p":0.03,"straggle_ms":300}'
    logger lab lablog "$URL0" lablogs
    logger pc1 witness "$URL0" witlogs
    fitter lab fitter "$URL0"
    vbench pc1 vb1 31 --runs 2 "${VB_COMMON[@]}" --coulomb 4e-4
    sleep 0.5
    bridge pc1 br1 bench-1 vb1 "$URL0"
    wait_bench_done vb1 70
    sleep 3
    finish br1 fitter lablog witness relay
}

scenario_lab_clock_forward() {
    ns_one lab
    echo "+0" > "$SCR/labclock"
    local FT; FT=$(faketime_env "$SCR/labclock")
    mkdir -p "$SCR/lablogs"
    bg lab lablog env $FT "$BIN/spindown-logger" --lcm-url "$URL0" --dir "$SCR/lablogs" --prefix lab --flush-interval 0.2
    bg lab fitter env $FT "$BIN/spindown-fitter" --lcm-url "$URL0" -v
    vbench lab vb1 41 --runs 2 "${VB_COMMON[@]}" --coulomb 3e-4
    sleep 0.5
    local t0; t0=$(t_now)
    bg lab br1 env $FT "$BIN/spindown-bridge" --device "$SCR/vb1.tty" --bench bench-1 --lcm-url "$URL0"
    sleep_until "$t0 + 2.5 + 3"
    echo "+3600" > "$SCR/labclock"; say "lab PC clock +3600 s"
    wait_bench_done vb1 70
    sleep 3
    finish br1 fitter lablog
}

scenario_bench_clock_forward_signed() {
    ns_two lab pc1
    "$BIN/spindown" keygen -o "$SCR/lab.key" > /dev/null 2>&1 || harness_fail "spindown keygen"
    local K=(--key "$SCR/lab.key")
    logger lab lablog "$URL0" lablogs "${K[@]}"
    fitter lab fitter "$URL0" "${K[@]}"
    echo "+0" > "$SCR/benchclock"
    local FT; FT=$(faketime_env "$SCR/benchclock")
    vbench pc1 vb1 51 --runs 2 "${VB_COMMON[@]}" --coulomb 3e-4
    sleep 0.5
    local t0; t0=$(t_now)
    bg pc1 br1 env $FT "$BIN/spindown-bridge" --device "$SCR/vb1.tty" --bench bench-1 --lcm-url "$URL0" "${K[@]}"
    sleep_until "$t0 + 2.5 + 3"
    echo "+40" > "$SCR/benchclock"; say "bench PC clock +40 s"
    wait_bench_done vb1 70
    sleep 3
    finish br1 fitter lablog relay
}

scenario_fitter_joins_late() {
    ns_one lab
    logger lab lablog "$URL0" lablogs
    # bench-1: powered lead-in (the pin reads the supply) of 6 s before each cut; bench-2: coasting early
    vbench lab vb1 61 --runs 2 --idle 2 --tail-s 4 --viscous 1.8e-7 --e0 3 --noise 0.003 --coulomb 4e-4 \
        --lead-in supply --supply 3.4 --lead-in-s 6
    vbench lab vb2 62 --runs 2 --idle 2 --tail-s 4 --viscous 1.8e-7 --e0 3 --noise 0.003 --coulomb 2e-4 \
        --lead-in-s 1
    sleep 0.5
    local t0; t0=$(t_now)
    bridge lab br1 bench-1 vb1 "$URL0"
    bridge lab br2 bench-2 vb2 "$URL0"
    sleep_until "$t0 + 3.5"              # bench-1 powered (cut at 6.5), bench-2 coasting (cut at 1.5)
    fitter lab fitter "$URL0"
    wait_bench_done vb1 70; wait_bench_done vb2 30
    sleep 3
    finish br1 br2 fitter lablog
}

scenario_logger_restart() {
    ns_one lab
    fitter lab fitter "$URL0"
    logger lab logger1 "$URL0" logsA
    vbench lab vb1 71 --runs 3 "${VB_COMMON[@]}" --coulomb 5e-4
    sleep 0.5
    local t0; t0=$(t_now)
    bridge lab br1 bench-1 vb1 "$URL0"
    sleep_until "$t0 + 2.5 + 3"
    stop logger1
    sleep 2
    logger lab logger2 "$URL0" logsB
    wait_bench_done vb1 80
    sleep 3
    finish br1 fitter logger2
}

scenario_replay_fast() {
    ns_one rec
    logger rec reclog "$URL0" reclogs
    fitter rec fitter "$URL0"
    vbench rec vb1 81 --runs 2 "${VB_COMMON[@]}" --coulomb 5e-4
    vbench rec vb2 82 --runs 2 "${VB_COMMON[@]}" --coulomb 4e-4
    sleep 0.5
    bridge rec br1 bench-1 vb1 "$URL0"
    bridge rec br2 bench-2 vb2 "$URL0"
    wait_bench_done vb1 60; wait_bench_done vb2 30
    sleep 3
    finish br1 br2 fitter reclog
    # the replay, on a PC of its own
    ns_one play
    logger play playlog "$URL0" playlogs
    fitter play replayfitter "$URL0"
    sleep 0.5
    local LOG; LOG=$(ls "$SCR"/reclogs/*.lcm | head -1)
    bg play player lcm-logplayer -s 5 --lcm-url="$URL0" --regexp='SPINDOWN\..*\.(SAMPLE|CONFIG)' "$LOG"
    wait_gone player 30 || harness_fail "lcm-logplayer -s 5 did not end within 30 s"
    sleep 3
    finish replayfitter playlog
}

scenario_concat_days() {
    ns_one mon
    logger mon monlog "$URL0" monlogs
    fitter mon monfitter "$URL0"
    vbench mon mon 91 --runs 2 "${VB_COMMON[@]}" --coulomb 4e-4
    sleep 0.5
    bridge mon monbr bench-1 mon "$URL0"
    wait_bench_done mon 60
    sleep 3
    finish monbr monfitter monlog
    # Tuesday: another motor (2.5x the Coulomb friction), the Arduino's clock from 0, a new bridge
    ns_one tue
    logger tue tuelog "$URL0" tuelogs
    fitter tue tuefitter "$URL0"
    vbench tue tue 92 --runs 2 --idle 2 --lead-in-s 4 --tail-s 4 --viscous 1.8e-7 --e0 3 --noise 0.003 --coulomb 1e-3
    sleep 0.5
    bridge tue tuebr bench-1 tue "$URL0"
    wait_bench_done tue 40
    sleep 3
    finish tuebr tuefitter tuelog
}

scenario_cable_swap() {
    ns_one lab
    logger lab lablog "$URL0" lablogs
    fitter lab fitter "$URL0"
    # motor X on bench-a (c4 3e-4, ~12.5 s coasts), motor Y on bench-b (c4 7.5e-4, ~5.5 s), started 6 s apart
    vbench lab vbx 101 --runs 3 "${VB_COMMON[@]}" --coulomb 3e-4
    vbench lab vby 102 --runs 4 --idle 2 --lead-in-s 3 --tail-s 4 --viscous 1.8e-7 --e0 3 --noise 0.003 --coulomb 7.5e-4
    sleep 0.5
    local t0; t0=$(t_now)
    bridge lab bra1 bench-a vbx "$URL0"
    sleep_until "$t0 + 6"
    bridge lab brb1 bench-b vby "$URL0"
    sleep_until "$t0 + 8"                # X coasting (cut 2.5 s, stop ~15 s); Y powered, not yet cut
    local out_us; out_us=$(now_us)
    stop bra1 & local p1=$!
    stop brb1 & local p2=$!
    wait "$p1" "$p2"
    sleep 1
    local in_us; in_us=$(now_us)
    bridge lab bra2 bench-a vby "$URL0"  # the cables the wrong way round
    bridge lab brb2 bench-b vbx "$URL0"
    echo "{\"out_us\": $out_us, \"in_us\": $in_us}" > "$SCR/swap.json"
    wait_bench_done vbx 75; wait_bench_done vby 30
    sleep 3
    finish bra2 brb2 fitter lablog
}

scenario_bridge_stall() {
    ns_one lab
    logger lab lablog "$URL0" lablogs
    fitter lab fitter "$URL0"
    vbench lab vb1 111 --runs 2 "${VB_COMMON[@]}" --coulomb 3e-4
    sleep 0.5
    local t0; t0=$(t_now)
    bridge lab br1 bench-1 vb1 "$URL0"
    sleep_until "$t0 + 2.5 + 3"
    kill -STOP "$(pid_of br1)"; say "bridge stopped (SIGSTOP)"
    sleep 4
    kill -CONT "$(pid_of br1)"; say "bridge continued"
    wait_bench_done vb1 70
    sleep 3
    finish br1 fitter lablog
}

fn="scenario_${NAME//-/_}"
declare -F "$fn" > /dev/null || harness_fail "no case $NAME"
"$fn"
say "scenario done; judging"
out=$(python3 "$HERE/judge.py" "$NAME" 2> "$SCR/judge.err"); rc=$?
printf '%s\n' "$out" > "$SCR/judge.out"
case $rc in
    0) echo "PASS" > "$SCR/verdict" ;;
    1) echo "FAIL: $(printf '%s' "$out" | head -8 | tr '\n' ';' | cut -c1-1500)" > "$SCR/verdict" ;;
    *) echo "HARNESS: $(printf '%s' "$out" | tail -1 | cut -c1-600) $(tail -2 "$SCR/judge.err" | tr '\n' ' ' | cut -c1-300)" > "$SCR/verdict" ;;
esac
