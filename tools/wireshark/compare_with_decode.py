#!/usr/bin/env python3
"""Checks the Wireshark dissector against `mocosim decode`.

For every session given, in three chunkings (as recorded; every chunk cut
into pieces of 1..7 bytes, so frames are split across packets; runs of
chunks from one side joined, so packets hold several frames), this exports
the session with `mocosim export --pcapng`, dissects it with tshark and
tools/wireshark/mocosim.lua, and compares the messages, in order and per
direction, with the transcript `mocosim decode` prints: for DMC v2 and
DFMoco the whole text (type, ID, every field, checksum verdict); for the
StackShot binary protocol the command, action, axis and checksum verdict.

  compare_with_decode.py MOCOSIM WORKDIR SESSION...
  compare_with_decode.py --mutants N --seed S [--mutants-only] MOCOSIM WORKDIR SESSION...

With --mutants, each session also gives N seeded mutants (bytes flipped,
inserted, deleted or repeated in one or two of its chunks, signs, digits,
spaces and line ends put in text, runs of junk up to 3000 bytes), each
compared the same way: agreement is a property of any traffic, not of the
golden sessions only. The same seed gives the same mutants; a mutant that
disagrees is kept in WORKDIR as SESSION-mutantK.jsonl and named with its
seed. --mutants-only leaves out the sessions themselves and their
rechunked forms.

Exit 0 when every session matches, 1 on a difference (the first is printed),
77 when tshark is not installed (CTest counts it as skipped; ci/setup-deps
installs it).
"""
import json
import os
import random
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DISSECTOR = os.path.join(HERE, "mocosim.lua")


def decode_messages(mocosim, session, protocol):
    out = subprocess.run([mocosim, "decode", "--no-time", session], check=True,
                         capture_output=True, text=True).stdout
    messages = []
    for line in out.splitlines():
        if line.startswith("host -> dev  "):
            messages.append(("host", line[len("host -> dev  "):].lstrip(" ")))
        elif line.startswith("dev  -> host  "):
            messages.append(("device", line[len("dev  -> host  "):]))
            if messages[-1][1].startswith("(the line switches to DfMoco mode"):
                protocol = "stackshot-dfmoco"
        elif "  event  " in line:
            # A recorded line switch to another protocol: the dissector
            # shows it on the first packet after it, whichever its side.
            event = json.loads(line[line.index("{"):])
            if event.get("event") == "line_switch" and event.get("protocol") != protocol:
                protocol = event["protocol"]
                messages.append(("*", "(the line switches to " + protocol + ")"))
    return messages


def tshark_messages(tshark, capture):
    env = dict(os.environ, HOME=os.environ.get("HOME", "/tmp"))
    out = subprocess.run(
        [tshark, "-n", "-X", "lua_script:" + DISSECTOR, "-r", capture, "-T", "fields",
         "-e", "mocosim.direction", "-e", "mocosim.skipped_so_far", "-e", "mocosim.message",
         "-E", "occurrence=a", "-E", "aggregator=\x1f"],
        check=True, capture_output=True, text=True, env=env).stdout
    messages = []
    junk_shown = set()  # sides with a packet marked for bytes skipped so far
    for line in out.splitlines():
        direction, _, rest = line.partition("\t")
        skipped, _, texts = rest.partition("\t")
        side = "host" if direction == "host->device" else "device"
        if skipped:
            junk_shown.add(side)
        if not texts:
            continue
        # A unit separator between messages: decode writes no control
        # character, while '|' or ',' can be in a message.
        for text in texts.split("\x1f"):
            switch = re.fullmatch(r"\(the line switches to [\w-]+\)", text)
            messages.append(("*" if switch else side, text))
    return messages, junk_shown


def key(protocol, message):
    side, text = message
    if protocol == "stackshot":
        problem = text.startswith("!! ")
        if problem:
            # A refused packet: header, data bytes, the reason and the
            # checksum note, the whole text.
            return (side, text)
        body = text
        m = re.match(r"(\S+) (\S+) axis=(\S+)", body)
        if m:
            body = " ".join(m.groups())
            if "[checksum byte differs from the default algorithm]" in text:
                body += " [checksum differs]"
        return (side, ("!! " if problem else "") + body)
    if " malformed: " in text:
        text = text[:text.index(" malformed: ")] + " malformed"
    if protocol in ("dfmoco", "stackshot-dfmoco") and text.startswith("!! "):
        text = "!! (does not parse)"
    return (side, text)


def keys(protocol, messages):
    """The keys of a transcript's messages; a StackShot line that switched to
    DfMoco mode carries DFMoco lines from the switch on."""
    out = []
    for m in messages:
        switch = re.fullmatch(r"\(the line switches to ([\w-]+)\)", m[1])
        if m[0] == "*" and switch:
            # A recorded line switch (docs/sessions.md "line_switch").
            protocol = switch.group(1)
            out.append(m)
            continue
        out.append(key(protocol, m))
        if protocol == "stackshot" and m[1].startswith("(the line switches to DfMoco mode"):
            protocol = "stackshot-dfmoco"
    return out


def rechunk(session_path, out_path, mode):
    """Writes the session with its chunks cut ("split") or joined ("merged")."""
    with open(session_path) as f:
        lines = [l for l in f.read().splitlines() if l.strip()]
    header, entries = lines[0], [json.loads(l) for l in lines[1:]]
    result = []
    if mode == "split":
        sizes = [1, 3, 7, 2, 5, 4, 6]
        n = 0
        for e in entries:
            if "hex" not in e:
                result.append(e)
                continue
            data = bytes.fromhex(e["hex"])
            at = 0
            while at < len(data):
                size = sizes[n % len(sizes)]
                n += 1
                result.append({"t_ns": e["t_ns"], "from": e["from"],
                               "hex": data[at:at + size].hex()})
                at += size
    else:
        for e in entries:
            if ("hex" in e and result and "hex" in result[-1]
                    and result[-1]["from"] == e["from"]):
                result[-1] = dict(result[-1], hex=result[-1]["hex"] + e["hex"])
            elif "hex" in e:
                result.append({"t_ns": e["t_ns"], "from": e["from"], "hex": e["hex"]})
            else:
                result.append(e)
    with open(out_path, "w") as f:
        f.write(header + "\n")
        for e in result:
            f.write(json.dumps(e) + "\n")


def compare(mocosim, tshark, workdir, session, label):
    with open(session) as f:
        protocol = json.loads(f.readline())["protocol"]
    capture = os.path.join(workdir, label + ".pcapng")
    subprocess.run([mocosim, "export", "--pcapng", session, "-o", capture], check=True,
                   capture_output=True)
    decoded = decode_messages(mocosim, session, protocol)
    want = keys(protocol, decoded)
    shown, junk_shown = tshark_messages(tshark, capture)
    got = keys(protocol, shown)
    for i, (w, g) in enumerate(zip(want, got)):
        if w != g:
            print(f"{label}: message {i + 1} differs\n  mocosim decode: {w}\n  tshark:         {g}")
            return False
    # What is pending when the traffic ends (a cut packet, frame or line, junk
    # after the last message) only decode can tell: a dissector sees packets,
    # never the end of the capture. Decode's lines past the dissector's must
    # begin with such a problem; what follows it is the rescan of the bytes
    # left pending (DMC frames a partial one hid). Junk among them must still
    # show in tshark, as a packet marked for bytes skipped so far.
    end_of_traffic = re.compile(r"!! (\d+ byte\(s\) of an (incomplete packet|unterminated line)|"
                                r"skipped \d+ byte\(s\) (at the end|outside any frame)|"
                                r"stream ended)")
    extra = decoded[len(got):]
    if len(want) < len(got) or (extra and not end_of_traffic.match(extra[0][1])):
        print(f"{label}: mocosim decode gives {len(want)} messages, tshark {len(got)}"
              + (f"; decode's last: {extra[-1]}" if extra else ""))
        return False
    firsts = {}
    for side, text in extra:
        firsts.setdefault(side, text)
    for side, text in firsts.items():
        # Junk after the last message (not the rescan of a pending frame).
        if text.startswith("!! skipped ") and side not in junk_shown:
            print(f"{label}: mocosim decode ends with '{text}' ({side}), "
                  "and tshark marks no packet of that side for skipped bytes")
            return False
    print(f"{label}: {len(want)} messages match ({protocol})")
    return True


def mutate(session_path, out_path, rng):
    """Writes a mutant of the session: one or two chunks changed."""
    with open(session_path) as f:
        lines = [l for l in f.read().splitlines() if l.strip()]
    header, entries = lines[0], [json.loads(l) for l in lines[1:]]
    chunks = [i for i, e in enumerate(entries) if "hex" in e]
    for _ in range(rng.randint(1, 2)):
        i = rng.choice(chunks)
        data = bytearray(bytes.fromhex(entries[i]["hex"]))
        at = rng.randrange(len(data) + 1)
        kind = rng.randrange(7)
        if kind == 0 and data:
            data[min(at, len(data) - 1)] ^= 1 << rng.randrange(8)
        elif kind == 1:
            data[at:at] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 12)))
        elif kind == 2 and data:
            del data[at:at + rng.randint(1, 8)]
        elif kind == 3 and data:
            piece = data[at:at + rng.randint(1, 16)]
            data[at:at] = piece
        elif kind == 4:
            data[at:at] = rng.choice([b"+", b"-", b"-0", b" ", b"  ", b"0", b"9" * 12, b"\r",
                                      b"\n", b"\r\n", b"x"])
        elif kind == 5:
            data[at:at] = bytes(rng.randrange(32, 127) for _ in range(rng.randint(1, 6)))
        else:
            # A run of junk, longer than a DMC receive buffer at times.
            data[at:at] = bytes(rng.randrange(256) for _ in range(rng.randint(13, 3000)))
        entries[i] = dict(entries[i], hex=bytes(data).hex())
    with open(out_path, "w") as f:
        f.write(header + "\n")
        for e in entries:
            f.write(json.dumps(e) + "\n")


def main(argv):
    mutants, seed, mutants_only = 0, 1, False
    args = argv[1:]
    while args and args[0] in ("--mutants", "--seed", "--mutants-only"):
        if args[0] == "--mutants-only":
            mutants_only = True
            args = args[1:]
            continue
        if len(args) < 2 or not args[1].isdigit():
            print(__doc__)
            return 2
        if args[0] == "--mutants":
            mutants = int(args[1])
        else:
            seed = int(args[1])
        args = args[2:]
    if len(args) < 3:
        print(__doc__)
        return 2
    mocosim, workdir, sessions = args[0], args[1], args[2:]
    tshark = shutil.which("tshark")
    if not tshark:
        print("tshark is not installed (Debian package tshark; ci/setup-deps installs it)")
        return 77
    os.makedirs(workdir, exist_ok=True)
    ok = True
    for session in sessions:
        name = os.path.splitext(os.path.basename(session))[0]
        if not mutants_only:
            ok &= compare(mocosim, tshark, workdir, session, name)
            for mode in ("split", "merged"):
                variant = os.path.join(workdir, f"{name}-{mode}.jsonl")
                rechunk(session, variant, mode)
                ok &= compare(mocosim, tshark, workdir, variant, f"{name}-{mode}")
        rng = random.Random(f"{seed}:{name}")
        for k in range(mutants):
            variant = os.path.join(workdir, f"{name}-mutant{k}.jsonl")
            mutate(session, variant, rng)
            if not compare(mocosim, tshark, workdir, variant, f"{name}-mutant{k} (seed {seed})"):
                print(f"  the mutant is kept as {variant} (--mutants {k + 1} --seed {seed} "
                      f"makes it again); mocosim decode {variant}")
                ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
