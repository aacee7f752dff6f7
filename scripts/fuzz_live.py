"""Hostile clients of sinew-live for scripts/fuzz_inputs.py (issue 33; docs/live.md, "Threat model").

A web page open in the user's browser can reach a server on the loopback interface: it can open a
WebSocket to it (carrying its own Origin, which the page cannot forge) and, by DNS rebinding, send
plain requests under its own host name (carrying that name as Host). sinew-live must answer only
its own page: a WebSocket handshake from any other Origin or to any other Host is refused, a plain
request to any other Host gets nothing, and after all of them the user's own page still gets its
page and its WebSocket (none of the refused ones holds a client slot).

campaign() starts `sinew-live --play` on the fuzzer's seed results, sends `count` requests, each a
random pick of the hostile forms below (Origins and Hosts of another site, of a look-alike name, of
another port or scheme, "null", file://, two Origin headers, ...), and classifies each:

  refused   a 4xx/5xx answer (the standard)
  accepted  101 to a hostile WebSocket, or 200 to a hostile Host (a failure)
  hang      no answer within the timeout (a failure)
  crash     the server is gone (a failure)

and a last check, `own`, that the user's page (GET / and the WebSocket with the server's own Origin)
is still served: `locked_out` when not (a failure).
"""
import os
import random
import re
import signal
import socket
import subprocess
import time

FAILURES = ("accepted", "hang", "crash", "locked_out")

# Origins of other pages, {port} the server's. None is this server's own (http://127.0.0.1:{port},
# http://localhost:{port}, http://[::1]:{port}); "https" or another port is another origin.
HOSTILE_ORIGINS = [
    "http://evil.example", "http://evil.example:{port}", "null", "file://",
    "http://127.0.0.1.evil.example", "http://127.0.0.1.evil.example:{port}",
    "http://localhost.evil.example:{port}", "http://127.0.0.1:{port}.evil.example",
    "http://127.0.0.1:{port}@evil.example", "http://evil.example@127.0.0.1:{port}",
    "https://127.0.0.1:{port}", "http://127.0.0.1:{other}", "http://localhost:{other}",
    "http://0.0.0.0:{port}", "http://127.0.0.2:{port}", "ws://127.0.0.1:{port}",
    "http://127.0.0.1", "http://localhost", "", "http://[::1].evil.example:{port}",
]
HOSTILE_HOSTS = [
    "evil.example", "evil.example:{port}", "127.0.0.1.evil.example:{port}",
    "localhost.evil.example:{port}", "127.0.0.1:{other}", "localhost:{other}", "",
    "127.0.0.1:{port}.evil.example", "rebind.evil.example:{port}",
]


def stop(proc):
    """Stops a server started in its own session: SIGTERM, then SIGKILL after 5 s. Returns whether
    it had to be killed (it hung)."""
    if proc.poll() is not None:
        return False
    os.killpg(proc.pid, signal.SIGTERM)
    try:
        proc.wait(timeout=5)
        return False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        return True


def _request(port, lines, timeout):
    """Sends one request (header lines) to the server; returns its status code, or None when it
    did not answer, or -1 when it could not be reached."""
    text = "\r\n".join(lines) + "\r\n\r\n"
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
            s.sendall(text.encode("utf-8", "surrogateescape"))
            data = b""
            deadline = time.time() + timeout
            while b"\r\n" not in data and time.time() < deadline:
                chunk = s.recv(4096)
                if not chunk:
                    break
                data += chunk
    except ConnectionRefusedError:
        return -1
    except (socket.timeout, OSError):
        return None
    m = re.match(rb"HTTP/1\.[01] (\d{3})", data)
    return int(m.group(1)) if m else None


def _websocket(host, origins):
    lines = ["GET /ws HTTP/1.1", f"Host: {host}", "Upgrade: websocket", "Connection: Upgrade",
             "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==", "Sec-WebSocket-Version: 13"]
    return lines + [f"Origin: {o}" for o in origins]


def _hostile(rng, port):
    """One hostile request: (label, header lines, the status that would mean it got in)."""
    own_host, own_origin = f"127.0.0.1:{port}", f"http://127.0.0.1:{port}"
    fill = dict(port=port, other=port + 1 if port < 65535 else port - 1)
    kind = rng.choice(["origin", "origin", "two_origins", "host", "ws_host"])
    if kind == "origin":
        o = rng.choice(HOSTILE_ORIGINS).format(**fill)
        if rng.random() < 0.3:  # the page cannot choose its Origin's case, but a program can
            o = "".join(c.upper() if rng.random() < 0.5 else c for c in o)
            if o.lower() in (own_origin, f"http://localhost:{port}", f"http://[::1]:{port}"):
                o = "http://EVIL.example"
        return f"ws origin {o!r}", _websocket(own_host, [o]), 101
    if kind == "two_origins":
        evil = rng.choice(HOSTILE_ORIGINS).format(**fill)
        pair = [own_origin, evil] if rng.random() < 0.5 else [evil, own_origin]
        return f"ws origins {pair!r}", _websocket(own_host, pair), 101
    h = rng.choice(HOSTILE_HOSTS).format(**fill)
    if kind == "host":
        return f"GET / host {h!r}", ["GET / HTTP/1.1", f"Host: {h}"], 200
    return f"ws host {h!r}", _websocket(h, [own_origin]), 101


def campaign(argv, run_dir, count, seed, timeout):
    """Runs the server (argv, in run_dir) and `count` hostile requests; returns (a Counter-like
    dict of classes, records, the server's output)."""
    counts, records = {}, []
    proc = subprocess.Popen(argv, cwd=run_dir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            start_new_session=True)
    out = b""
    os.set_blocking(proc.stdout.fileno(), False)
    port = None
    deadline = time.time() + max(timeout, 20)
    while time.time() < deadline and proc.poll() is None and port is None:
        out += proc.stdout.read() or b""
        m = re.search(rb"open http://[^:/\s]+:(\d+)", out)
        if m:
            port = int(m.group(1))
        time.sleep(0.05)

    def tally(cls, label, status):
        counts[cls] = counts.get(cls, 0) + 1
        records.append({"target": "live_origin", "mutation": label, "class": cls,
                        "status": status})

    try:
        if port is None:
            tally("crash" if proc.poll() is not None else "hang", "start", None)
            return counts, records, out.decode("utf-8", "replace")
        rng = random.Random(f"{seed}:live_origin")
        for _ in range(count):
            label, lines, inside = _hostile(rng, port)
            status = _request(port, lines, timeout=5)
            if proc.poll() is not None or status == -1:
                tally("crash", label, status)
                break
            tally("hang" if status is None else "accepted" if status == inside else "refused",
                  label, status)
        # The user's own page still gets in: the page, then its WebSocket.
        page = _request(port, ["GET / HTTP/1.1", f"Host: 127.0.0.1:{port}"], timeout=5)
        ws = _request(port, _websocket(f"127.0.0.1:{port}", [f"http://127.0.0.1:{port}"]),
                      timeout=5)
        tally("own" if page == 200 and ws == 101 else "locked_out",
              "own page and WebSocket", [page, ws])
    finally:
        stop(proc)
        os.set_blocking(proc.stdout.fileno(), True)
        out += proc.stdout.read() or b""
    return counts, records, out.decode("utf-8", "replace")
