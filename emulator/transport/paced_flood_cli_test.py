#!/usr/bin/env python3
"""End to end: a host that writes thousands of requests in one write to
`mocosim` with its default pacing gets every one answered, in order, and the
recording decodes with `mocosim decode --strict` (issue: the paced link lost,
repeated and reordered host bytes once a host wrote ~4 KB ahead of the line).

  paced_flood_cli_test.py MOCOSIM [--lines 3000]

A DFMoco Arduino on a PTY (57600 baud, paced): `mp 1`..`mp 4` lines written
in one go. The recording's host bytes must equal what was written, byte for
byte; every reply must be `mp <m> 0` (no `parse error`, no `mp mp 2`), and
the replies must follow the requests' order. Replies themselves may be fewer
than the requests: the sketch's 16-slot transmit queue drops messages when
requests come faster than their replies can leave (FACTS.md, DFMoco), which
a 6-byte request and an 8-byte reply at one baud rate guarantee.
Exit 0 when all hold, 1 otherwise."""

import json

import os
import select
import signal
import subprocess
import sys
import tempfile
import termios
import time
import tty


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def main():
    mocosim = sys.argv[1]
    lines = int(sys.argv[3]) if len(sys.argv) > 3 and sys.argv[2] == "--lines" else 3000
    with tempfile.TemporaryDirectory() as tmp:
        pty_path = os.path.join(tmp, "dfmoco")
        rec = os.path.join(tmp, "flood.jsonl")
        log = open(os.path.join(tmp, "mocosim.log"), "w+")
        proc = subprocess.Popen([mocosim, "dfmoco", "--pty", pty_path, "--record", rec],
                                stdout=subprocess.DEVNULL, stderr=log)
        try:
            deadline = time.monotonic() + 30
            while not os.path.exists(pty_path):
                if proc.poll() is not None or time.monotonic() > deadline:
                    log.seek(0)
                    fail("mocosim did not create its PTY: " + log.read())
                time.sleep(0.05)
            fd = os.open(pty_path, os.O_RDWR | os.O_NOCTTY)
            tty.setraw(fd)
            requests = "".join("mp %d\r\n" % (1 + i % 4) for i in range(lines)).encode()
            # Written as fast as the PTY takes it: far ahead of the line rate.
            received = b""
            sent = 0
            replies = []
            deadline = time.monotonic() + 120
            last_rx = time.monotonic()
            while sent < len(requests) or time.monotonic() - last_rx < 2.0:
                if time.monotonic() > deadline:
                    fail("no end after 120 s: %d of %d bytes written" % (sent, len(requests)))
                wlist = [fd] if sent < len(requests) else []
                r, w, _ = select.select([fd], wlist, [], 0.5)
                if w:
                    os.set_blocking(fd, False)
                    try:
                        sent += os.write(fd, requests[sent:])
                    except BlockingIOError:
                        pass
                    os.set_blocking(fd, True)
                if r:
                    received += os.read(fd, 65536)
                    last_rx = time.monotonic()
                    *done, received = received.split(b"\n")
                    replies += [d.rstrip(b"\r").decode(errors="replace") for d in done]
            replies = [x for x in replies if not x.startswith("hi ")]  # the power-on greeting
            asked = [1 + i % 4 for i in range(lines)]
            k = 0
            for i, reply in enumerate(replies):
                parts = reply.split(" ")
                if len(parts) != 3 or parts[0] != "mp" or parts[2] != "0" or \
                        parts[1] not in ("1", "2", "3", "4"):
                    fail("reply %d is %r: host bytes reached the device damaged" % (i, reply))
                while k < lines and asked[k] != int(parts[1]):
                    k += 1
                if k == lines:
                    fail("reply %d (%r) is out of the requests' order" % (i, reply))
                k += 1
            if len(replies) < 100:
                fail("only %d replies to %d requests" % (len(replies), lines))
            os.close(fd)
        finally:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                fail("mocosim did not stop on SIGINT")
        host = bytearray()
        with open(rec) as f:
            for line in f:
                entry = json.loads(line)
                if entry.get("from") == "host":
                    host += bytes.fromhex(entry["hex"])
        if bytes(host) != requests:
            at = next((i for i in range(min(len(host), len(requests)))
                       if host[i] != requests[i]), min(len(host), len(requests)))
            fail("the device received %d bytes of %d, first difference at byte %d"
                 % (len(host), len(requests), at))
        out = subprocess.run([mocosim, "decode", "--strict", rec], capture_output=True, text=True)
        if out.returncode != 0:
            problems = [l for l in out.stdout.splitlines() if "!!" in l][:5]
            fail("decode --strict exit %d: %s" % (out.returncode, problems))
        print("PASS: %d requests written at once reached the device intact; %d replies, in "
              "order; the recording decodes strictly" % (lines, len(replies)))


if __name__ == "__main__":
    main()
