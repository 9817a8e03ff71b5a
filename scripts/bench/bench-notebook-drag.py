"""The kernel side of scripts/bench/bench-notebook-drag: runs the drag in a fresh
kernel through nbclient and prints one JSON line."""

import json
import os
import sys
import textwrap

import nbclient
import nbformat

seconds, size = float(sys.argv[1]), int(sys.argv[2])
samples = os.path.join(os.environ.get("GLINT_DATA", os.path.expanduser("~/.cache/glint")), "samples")
mni = os.path.join(samples, "mni152_t1_09a.nii.gz")

SETUP = f"""
import asyncio, json, time
import numpy as np
import glint

def comm_update(w, state):
    w._handle_msg({{"content": {{"data": {{"method": "update", "state": state,
                                          "buffer_paths": []}}}}, "buffers": []}})

def comm_event(w, event):
    w._handle_msg({{"content": {{"data": {{"method": "custom", "content": event}}}}, "buffers": []}})

viewer = glint.Viewer({mni!r}, size=({size}, {size}), lighting={{"model": "local"}})
canvas = viewer.canvas
taken = [-1]          # the last event the kernel took
frames = []           # (time sent, last event taken when its render began, purpose)
render_from = [None]
orig_frame, orig_send = viewer._frame, canvas.send

def frame():
    render_from[0] = taken[0]
    return orig_frame()

def send(msg, buffers=None):
    orig_send(msg, buffers)
    if msg.get("type") == "framebufferdata":
        frames.append((time.perf_counter(), render_from[0], viewer._last[1]))
        # The browser acknowledges at once.
        comm_update(canvas, {{"_frame_feedback": {{"index": msg["index"], "timestamp": time.time(),
                                                  "localtime": time.time()}}}})

viewer._frame = frame
canvas.send = send
comm_update(canvas, {{"_has_visible_views": True}})
"""

DRAG = f"""
await asyncio.sleep(1.0)              # the first full frame
frames.clear()
n = int({seconds} * 60)
t0 = time.perf_counter() + 0.05
due = [t0 + i / 60 for i in range(n)]
def ev(kind, i):
    return {{"type": kind, "x": 100 + i * 0.8, "y": 100 + (i % 40) * 0.5, "button": 1,
             "buttons": [1], "modifiers": [], "ntouches": 0, "touches": {{}},
             "timestamp": time.time()}}
comm_event(canvas, ev("pointer_down", 0))
for i in range(n):
    wait = due[i] - time.perf_counter()
    if wait > 0:
        await asyncio.sleep(wait)
    else:
        await asyncio.sleep(0)
    taken[0] = i
    comm_event(canvas, ev("pointer_move", i))
end_drag = time.perf_counter()
comm_event(canvas, ev("pointer_up", n))
await asyncio.sleep(0.6)
drag = [f for f in frames if f[2] == "interactive"]
lat = []
for i in range(n):
    after = [t for (t, e, p) in frames if e >= i]
    if after:
        lat.append((after[0] - due[i]) * 1e3)
lat.sort()
q = lambda p: lat[min(len(lat) - 1, int(p * len(lat)))]
print(json.dumps({{"size": {size}, "events": n, "drag_s": round(end_drag - t0, 2),
    "drag_frames": len(drag), "fps": round(len(drag) / (end_drag - t0), 1),
    "latency_ms": {{"median": round(q(0.5), 1), "p95": round(q(0.95), 1), "max": round(lat[-1], 1)}},
    "full_frames_after": len([f for f in frames if f[2] == "full"])}}))
"""

nb = nbformat.v4.new_notebook()
nb.cells = [nbformat.v4.new_code_cell(textwrap.dedent(c)) for c in (SETUP, DRAG)]
nbclient.NotebookClient(nb, timeout=600, kernel_name="python3").execute()
out = "".join(o.get("text", "") for o in nb.cells[1].outputs if o.output_type == "stream")
print(out.strip())
