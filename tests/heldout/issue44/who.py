#!/usr/bin/env python3
"""Held-out issue 44, case who-may-see: Host header (DNS rebinding), a class connecting at once, the docs.

    who.py LOCAL_PORT LAN_ADDR LAN_PORT WEB_PID DOCS_DIR BENCH

Prints one line: "PASS who-may-see: ..." or "FAIL who-may-see: why". Standard library only; every
socket has a timeout. Run inside the test's network namespace (127.0.0.1 and LAN_ADDR are its own).
"""
import os
import re
import signal
import socket
import sys
import time

NAME = "who-may-see"


def request(addr, port, path, host, timeout=3.0, read_s=2.0):
    """One HTTP/1.1 GET with the given Host header; returns (status or None, first bytes of the body)."""
    s = socket.create_connection((addr, port), timeout=timeout)
    try:
        hdr = f"GET {path} HTTP/1.1\r\n"
        if host is not None:
            hdr += f"Host: {host}\r\n"
        hdr += "Accept: */*\r\nConnection: close\r\n\r\n"
        s.sendall(hdr.encode("latin1"))
        data = b""
        end = time.monotonic() + read_s
        s.settimeout(0.3)
        while time.monotonic() < end and len(data) < 65536:
            try:
                chunk = s.recv(65536)
            except socket.timeout:
                if b"\r\n\r\n" in data and not path.startswith("/events"):
                    break
                continue
            if not chunk:
                break
            data += chunk
        m = re.match(rb"HTTP/1\.[01] (\d{3})", data)
        head, _, body = data.partition(b"\r\n\r\n")
        return (int(m.group(1)) if m else None), body[:4096]
    finally:
        s.close()


def listen_queue(port):
    """Connections waiting in the accept queue of the LISTEN socket on 127.0.0.1:port (/proc/net/tcp rx_queue)."""
    want = "0100007F:%04X" % port
    with open("/proc/net/tcp") as f:
        for line in f.readlines()[1:]:
            x = line.split()
            if x[1] == want and x[3] == "0A":
                return int(x[4].split(":")[1], 16)
    return -1


def leaks(body):
    return any(x in body for x in (b'"benches"', b"event:", b"data:", b"t_s,value", b'"last_fit"'))


def main():
    lport, lan, lanport, pid, docs, bench = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5], sys.argv[6]
    lport = int(lport)
    bad = []
    notes = []
    paths = ["/", "/api/state", "/events", f"/bench/{bench}", f"/bench/{bench}/runs/1.csv"]

    # 1. what a projector or a student on this PC uses must work
    for host in (f"127.0.0.1:{lport}", f"localhost:{lport}"):
        st, body = request("127.0.0.1", lport, "/api/state", host)
        if st != 200 or b'"benches"' not in body:
            bad.append(f"Host {host} (this PC) refused: /api/state {st}")
    st, body = request(lan, lanport, "/api/state", f"{lan}:{lanport}")
    if st != 200 or b'"benches"' not in body:
        bad.append(f"a listener on the lab LAN address refuses its own address as Host ({lan}:{lanport}): {st}")

    # 2. a DNS-rebinding page's requests carry the attacker's name in Host: nothing of the lab for them
    evil = [f"attacker.example:{lport}", f"127.0.0.1.attacker.example:{lport}", f"localhost.attacker.example:{lport}", "attacker.example"]
    served = []
    for host in evil:
        for path in paths:
            try:
                st, body = request("127.0.0.1", lport, path, host, read_s=1.0 if path == "/events" else 2.0)
            except OSError as e:
                st, body = None, b""
                notes.append(f"{path} {host}: {e}")
            if st is None or not (400 <= st < 500) or leaks(body):
                served.append(f"{path} as {host.split(':')[0]} -> {st}{' with lab data' if leaks(body) else ''}")
    for path in ("/api/state", "/events"):
        st, body = request(lan, lanport, path, f"rebind.attacker.example:{lanport}")
        if st is None or not (400 <= st < 500) or leaks(body):
            served.append(f"LAN listener {path} as rebind.attacker.example -> {st}")
    if served:
        bad.append(f"{len(served)} requests with a foreign Host header answered (want 4xx, no data): " + "; ".join(served[:6]) + (" …" if len(served) > 6 else ""))

    # 3. a class opening the page at the same moment while the server is busy for 2.5 s: how many
    #    connections the kernel holds for the server (the LISTEN socket's accept queue in /proc/net/tcp;
    #    a client's own "connected" is no measure: its final ACK may have been dropped by a full queue)
    n = 32
    socks = []
    queued = -1
    os.kill(pid, signal.SIGSTOP)
    try:
        for _ in range(n):
            c = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            c.setblocking(False)
            try:
                c.connect(("127.0.0.1", lport))
            except BlockingIOError:
                pass
            socks.append(c)
        time.sleep(2.5)
        queued = listen_queue(lport)
    finally:
        os.kill(pid, signal.SIGCONT)
        for c in socks:
            c.close()
    if queued < n:
        bad.append(f"of {n} pages opened at once while the server was busy 2.5 s, {queued} were queued for it (the rest wait for SYN retries: listen backlog too small)")

    # 4. the docs say what the web page exposes and how
    try:
        sec = open(os.path.join(docs, "security.md"), encoding="utf-8").read()
    except OSError as e:
        sec = ""
        bad.append(f"docs/security.md unreadable: {e}")
    miss = []
    if "spindown-web" not in sec:
        miss.append("spindown-web")
    if not re.search(r"\bHost\b", sec):
        miss.append("the Host header")
    if not re.search(r"rebind", sec, re.I):
        miss.append("DNS rebinding")
    if not re.search(r"0\.0\.0\.0|lab (LAN|network)|LAN address|--listen", sec):
        miss.append("what listening on the lab network exposes")
    if not re.search(r"(viewer|page|browser)s?[^.]{0,200}\bkey\b|\bkey\b[^.]{0,200}(viewer|page|browser)", sec, re.I | re.S):
        miss.append("what the key does for viewers")
    if miss:
        bad.append("docs/security.md says nothing of: " + ", ".join(miss))

    if bad:
        print(f"FAIL {NAME}: " + " | ".join(bad))
    else:
        print(f"PASS {NAME}: own and LAN Host served; {len(evil) * len(paths) + 2} foreign-Host requests refused; {queued}/{n} queued at once; docs cover the page")


if __name__ == "__main__":
    try:
        main()
    except Exception as e:  # a crash is a failure with its reason, never a skip
        print(f"FAIL {NAME}: error: {type(e).__name__}: {e}")
