"""Write a PNG screenshot of the Rerun web viewer showing a saved recording (.rrd), fully headless.

Usage::

    .venv/bin/python tools/screenshot_rerun.py REC.rrd OUT.png [--width 1600] [--height 1000] [--wait 120]

How it works: ``rerun --serve-web RECORDING.rrd`` serves the recording over gRPC and the web viewer over
HTTP on free local ports. Headless Chromium, rendering WebGL in software through SwiftShader, opens the
viewer and is driven over the DevTools protocol through ``--remote-debugging-pipe`` (standard library
only: no websocket client, no Playwright). The viewer loads the recording in a small page (software
rendering is slow and the viewer ingests data frame by frame), then the page is resized and the PNG is
taken once three captures in a row, half a second apart, are identical. ``--wait`` bounds the whole wait;
on 2 busy cores a small recording takes 16-30 s, a 60 MB one 65-80 s.

The recording's own blueprint decides the layout. A live viewer follows the data, so the time cursor
sits at the end of the recording; give time series views
``axis_x=rrb.TimeAxis(view_range=rrb.TimeRange(start=rrb.TimeRangeBoundary.infinite(),
end=rrb.TimeRangeBoundary.infinite()))`` to plot the whole run instead of a window around the cursor.

Needs Debian's Chromium (``apt-get install chromium``) and the ``rerun`` executable of ``rerun-sdk``.
"""

from __future__ import annotations

import argparse
import base64
import collections
import contextlib
import fcntl
import json
import os
import select
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.parse
from collections.abc import Iterator
from pathlib import Path
from typing import Any

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--disable-dev-shm-usage",
    "--mute-audio",
    "--hide-scrollbars",
    "--force-device-scale-factor=1",
    # No GPU here: WebGL2 through ANGLE on SwiftShader (software). Do not add --disable-gpu.
    "--use-gl=angle",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    # The page links Google fonts; fail such lookups at once instead of waiting on the network.
    "--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1",
    "--remote-debugging-pipe",
]

# Polled in the page: the viewer's index.html sets window._handle once the wasm app has started, and the
# encoded viewer state names an `about:recording?...recording_id=` route once a recording is shown.
STATUS_JS = """(() => {
  const h = window._handle;
  if (!h) { const c = document.getElementById("center_text"); return "loading: " + (c ? c.innerText : ""); }
  if (h.has_panicked()) return "panic: " + h.panic_message();
  const state = new TextDecoder("latin1").decode(h.viewer_state());
  return state.includes("recording_id=") ? "recording" : "started";
})()"""

HIDE_PANELS_JS = (
    "for (const p of ['top', 'blueprint', 'selection', 'time']) _handle.override_panel_state(p, 'hidden')"
)


class ScreenshotError(RuntimeError):
    """A failure with a one-line explanation for the user."""


def free_ports(count: int) -> list[int]:
    """Distinct TCP ports that were free on 127.0.0.1 a moment ago."""
    with contextlib.ExitStack() as stack:
        socks = [stack.enter_context(socket.socket()) for _ in range(count)]
        for sock in socks:
            sock.bind(("127.0.0.1", 0))
        return [sock.getsockname()[1] for sock in socks]


def log_tail(path: Path, lines: int = 5, grep: str = "") -> str:
    text = path.read_text(errors="replace").splitlines() if path.exists() else []
    return " | ".join([line.strip() for line in text if grep in line][-lines:])


@contextlib.contextmanager
def process_group(cmd: list[str], log: Path, **kw: Any) -> Iterator[subprocess.Popen[bytes]]:
    """Run ``cmd`` in its own process group; kill the whole group on exit, even on error."""
    with log.open("wb") as out:
        proc = subprocess.Popen(
            cmd, stdin=subprocess.DEVNULL, stdout=out, stderr=out, start_new_session=True, **kw
        )
    try:
        yield proc
    finally:
        for sig, grace in ((signal.SIGTERM, 5.0), (signal.SIGKILL, 5.0)):
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, sig)
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(grace)
                break


@contextlib.contextmanager
def serve_recording(rrd: Path, workdir: Path, deadline: float) -> Iterator[str]:
    """Run ``rerun --serve-web`` on ``rrd``; yield the web viewer's URL once both of its ports listen."""
    rerun = Path(sys.executable).with_name("rerun")
    exe = str(rerun) if rerun.exists() else shutil.which("rerun")
    if exe is None:
        raise ScreenshotError("the `rerun` executable was not found; install it with: pip install rerun-sdk")
    grpc_port, web_port = free_ports(2)
    cmd = [exe, "--serve-web", str(rrd), "--bind", "127.0.0.1"]
    cmd += ["--port", str(grpc_port), "--web-viewer-port", str(web_port)]
    log = workdir / "rerun.log"
    with process_group(cmd, log, env={**os.environ, "NO_COLOR": "1"}) as proc:
        for port in (grpc_port, web_port):
            while True:
                if proc.poll() is not None:
                    raise ScreenshotError(f"rerun exited with code {proc.returncode}: {log_tail(log)}")
                with socket.socket() as sock:
                    if sock.connect_ex(("127.0.0.1", port)) == 0:
                        break
                if time.monotonic() > deadline:
                    raise ScreenshotError(f"rerun did not listen on port {port}: {log_tail(log)}")
                time.sleep(0.2)
        proxy = f"rerun+http://127.0.0.1:{grpc_port}/proxy"
        yield f"http://127.0.0.1:{web_port}/?url={urllib.parse.quote(proxy, safe='')}"


class Chromium:
    """Minimal DevTools-protocol client for a headless Chromium started with ``--remote-debugging-pipe``."""

    def __init__(self, to_browser: int, from_browser: int, log: Path) -> None:
        self.to_browser, self.from_browser, self.log = to_browser, from_browser, log
        self.buffer = b""
        self.next_id = 0
        self.session: str | None = None

    def call(self, method: str, params: dict[str, Any] | None = None, timeout: float = 60) -> dict[str, Any]:
        self.next_id += 1
        message: dict[str, Any] = {"id": self.next_id, "method": method, "params": params or {}}
        if self.session is not None:
            message["sessionId"] = self.session
        try:
            os.write(self.to_browser, json.dumps(message).encode() + b"\0")
        except OSError as err:
            raise ScreenshotError(f"chromium exited ({method}): {log_tail(self.log)}") from err
        deadline = time.monotonic() + timeout
        while True:
            while b"\0" in self.buffer:
                raw, self.buffer = self.buffer.split(b"\0", 1)
                reply = json.loads(raw)
                if reply.get("id") == self.next_id:
                    if "error" in reply:
                        raise ScreenshotError(f"chromium: {method} failed: {reply['error'].get('message')}")
                    return dict(reply["result"])
            ready, _, _ = select.select([self.from_browser], [], [], max(0.0, deadline - time.monotonic()))
            chunk = os.read(self.from_browser, 1 << 20) if ready else b""
            if not chunk:
                why = "did not answer" if not ready else "exited"
                raise ScreenshotError(f"chromium {why} ({method}): {log_tail(self.log)}")
            self.buffer += chunk

    def evaluate(self, expression: str) -> Any:
        reply = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True})
        return reply["result"].get("value")

    def screenshot(self) -> str:
        """The page as a base64-encoded PNG."""
        return str(self.call("Page.captureScreenshot", {"format": "png"})["data"])

    def resize(self, width: int, height: int) -> None:
        metrics = {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}
        self.call("Emulation.setDeviceMetricsOverride", metrics)

    def settle(self, frames: int, deadline: float) -> tuple[bool, str]:
        """Capture until ``frames`` captures in a row are identical; at the deadline, False and the last."""
        last = collections.deque([self.screenshot()], maxlen=frames)
        while len(last) < frames or len(set(last)) > 1:
            if time.monotonic() > deadline:
                return False, last[-1]
            time.sleep(0.5)
            last.append(self.screenshot())
        return True, last[-1]


@contextlib.contextmanager
def start_chromium(executable: str, width: int, height: int, workdir: Path) -> Iterator[Chromium]:
    """Start headless Chromium with a fresh profile; yield a client attached to a new page."""
    cmd_read, cmd_write = os.pipe()
    reply_read, reply_write = os.pipe()

    def child_fds() -> None:  # the DevTools pipe must be fds 3 (commands in) and 4 (replies out)
        high_in = fcntl.fcntl(cmd_read, fcntl.F_DUPFD, 10)
        high_out = fcntl.fcntl(reply_write, fcntl.F_DUPFD, 10)
        os.dup2(high_in, 3)
        os.dup2(high_out, 4)

    profile = workdir / "profile"
    cmd = [executable, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", f"--window-size={width},{height}"]
    log = workdir / "chromium.log"
    try:
        with process_group([*cmd, "about:blank"], log, preexec_fn=child_fds, close_fds=False):
            os.close(cmd_read)
            os.close(reply_write)
            browser = Chromium(cmd_write, reply_read, log)
            target = browser.call("Target.createTarget", {"url": "about:blank"})["targetId"]
            attached = browser.call("Target.attachToTarget", {"targetId": target, "flatten": True})
            browser.session = attached["sessionId"]
            yield browser
    finally:
        for fd in (cmd_read, cmd_write, reply_read, reply_write):
            with contextlib.suppress(OSError):
                os.close(fd)


def take_screenshot(
    rrd: Path, out: Path, width: int, height: int, wait: float, chromium: str, hide_panels: bool
) -> bool:
    """Write the PNG; return False when the viewer never stopped changing (the last frame is written)."""
    deadline = time.monotonic() + wait
    with tempfile.TemporaryDirectory(prefix="screenshot_rerun_", ignore_cleanup_errors=True) as tmp:
        workdir = Path(tmp)
        with (
            serve_recording(rrd, workdir, deadline) as url,
            start_chromium(chromium, width, height, workdir) as browser,
        ):
            # Software rendering is slow and the viewer ingests data frame by frame: load the recording
            # into a small page, which draws much faster, then resize it for the screenshot.
            browser.resize(max(320, width // 4), max(200, height // 4))
            browser.call("Page.navigate", {"url": url})
            status = ""
            while status != "recording":
                if status.startswith("panic") or "error occurred" in status or "too old" in status:
                    raise ScreenshotError(f"the web viewer failed: {' '.join(status.split())}")
                if time.monotonic() > deadline:
                    what = "showed no recording" if status == "started" else f"did not start ({status!r})"
                    error = log_tail(workdir / "rerun.log", 1, grep=" ERROR ")
                    said = f"; rerun said: {error}" if error else f" (viewer URL: {url})"
                    raise ScreenshotError(f"the web viewer {what} within {wait:g} s{said}")
                time.sleep(0.5)
                status = str(browser.evaluate(STATUS_JS))
            if hide_panels:
                browser.evaluate(HIDE_PANELS_JS)
            browser.settle(2, deadline)
            browser.resize(width, height)
            settled, png = browser.settle(3, deadline)
        out.parent.mkdir(parents=True, exist_ok=True)
        partial = out.with_name(f".{out.name}.tmp")
        partial.write_bytes(base64.b64decode(png))
        partial.replace(out)  # a reader never sees half a PNG
        return settled


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("recording", type=Path, help="the .rrd file to show")
    parser.add_argument("out", type=Path, help="the PNG to write")
    parser.add_argument("--width", type=int, default=1600, help="viewport width in pixels (default 1600)")
    parser.add_argument("--height", type=int, default=1000, help="viewport height in pixels (default 1000)")
    parser.add_argument("--wait", type=float, default=120, help="time limit in seconds (default 120)")
    parser.add_argument("--hide-panels", action="store_true", help="show only the views, no side panels")
    parser.add_argument("--chromium", default=None, help="Chromium executable (default: chromium on PATH)")
    args = parser.parse_args(argv)

    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # so that the cleanup below still runs
    chromium = args.chromium or shutil.which("chromium") or shutil.which("chromium-browser")
    try:
        if chromium is None or shutil.which(chromium) is None:
            raise ScreenshotError("chromium was not found; install it with: apt-get install chromium")
        if not args.recording.is_file():
            raise ScreenshotError(f"no such recording: {args.recording}")
        start = time.monotonic()
        size = (args.width, args.height)
        settled = take_screenshot(args.recording, args.out, *size, args.wait, chromium, args.hide_panels)
    except ScreenshotError as err:
        print(f"screenshot_rerun: error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    if not settled:
        print(f"screenshot_rerun: warning: the viewer still changed after {args.wait:g} s", file=sys.stderr)
    print(f"wrote {args.out} ({args.width}x{args.height}) in {time.monotonic() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
