"""glint.Viewer (the notebook viewer, issue 45) and docs/notebook.ipynb.

The widget runs in a real kernel: a notebook executed by nbclient makes a viewer,
plays the browser's part through the widget's comm (the frame buffer's visible-view
and frame-feedback state updates, and pointer events as jupyter_rfb's front end sends
them: custom messages), and checks that frames arrive, differ after an orbit, and that
viewer.scene followed the drag. The browser itself is not run here (CI time): the
JupyterLab screenshot is made by scripts/notebook-screenshot.
"""

import json
import pathlib
import queue
import textwrap
import time

import numpy as np
import pytest

from conftest import require_module, ran

DOCS = pathlib.Path(__file__).resolve().parents[3] / "docs"


def _modules():
    for name in ("jupyter_rfb", "ipywidgets", "nbclient", "nbformat", "ipykernel"):
        require_module(name)
    import nbclient
    import nbformat

    return nbclient, nbformat


def _run(cells, cwd, timeout=300):
    """Runs code cells in a fresh kernel (this interpreter's); returns the notebook."""
    nbclient, nbformat = _modules()
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(textwrap.dedent(c)) for c in cells]
    client = nbclient.NotebookClient(nb, timeout=timeout, kernel_name="python3",
                                     resources={"metadata": {"path": str(cwd)}})
    client.execute()
    return nb


def _output(nb, i):
    """The stdout of cell i."""
    return "".join(o.get("text", "") for o in nb.cells[i].outputs if o.output_type == "stream")


# The browser's side of the widget, as messages through the comm: the model's
# state updates (a view is visible; frame feedback) and custom messages (events).
BROWSER = '''
import asyncio, time
import numpy as np
import glint

def comm_update(widget, state):
    # What the front end's model.save_changes() sends: an update message.
    widget._handle_msg({"content": {"data": {"method": "update", "state": state,
                                             "buffer_paths": []}}, "buffers": []})

def comm_event(widget, event):
    # What jupyter_rfb's front end sends for a pointer or wheel event.
    widget._handle_msg({"content": {"data": {"method": "custom", "content": event}},
                        "buffers": []})

def ack(canvas):
    comm_update(canvas, {"_frame_feedback": {"index": canvas._rfb_frame_index,
                                             "timestamp": time.time(),
                                             "localtime": time.time()}})

def pointer(kind, x, y, buttons):
    return {"type": kind, "x": x, "y": y, "button": 1, "buttons": buttons,
            "modifiers": [], "ntouches": 0, "touches": {}, "timestamp": time.time()}

async def settle(viewer, seconds=1.0):
    # Lets the kernel's event loop run (the draws and the settle timer), acking
    # every frame the widget sends, until nothing more comes.
    end = time.time() + seconds
    while time.time() < end:
        ack(viewer.canvas)
        await asyncio.sleep(0.02)
'''


def test_viewer_in_a_kernel_streams_frames_and_follows_a_drag(mni_path, tmp_path):
    nb = _run([
        BROWSER,
        f"""
        viewer = glint.Viewer({str(mni_path)!r}, size=(96, 96))
        # Run All: a snapshot before the browser shows the widget is not sent then
        # (it could be lost), but when a view appears, though no new frame is owed.
        snap = viewer.snapshot()
        unseen = viewer.canvas._rfb_frame_index
        comm_update(viewer.canvas, {{"_has_visible_views": True}})
        """,
        """
        await settle(viewer)
        shown = [unseen, viewer.canvas._rfb_frame_index,
                 bool(np.array_equal(viewer.canvas._rfb_last_frame, snap))]
        first = viewer.canvas._rfb_last_frame.copy()
        sent_before = viewer.canvas._rfb_frame_index
        az0 = viewer.scene.camera["azimuth"]
        comm_event(viewer.canvas, pointer("pointer_down", 40, 40, [1]))
        for x in range(42, 82, 4):
            comm_event(viewer.canvas, pointer("pointer_move", x, 44, [1]))
            await asyncio.sleep(0.01)
            ack(viewer.canvas)
        comm_event(viewer.canvas, pointer("pointer_up", 82, 44, []))
        await settle(viewer)
        after = viewer.canvas._rfb_last_frame.copy()
        print(json.dumps({
            "first_shape": first.shape, "after_shape": after.shape,
            "sent": [sent_before, viewer.canvas._rfb_frame_index],
            "diff": float(np.abs(first.astype(int) - after.astype(int)).mean()),
            "az": [az0, viewer.scene.camera["azimuth"]],
            "elevation": viewer.scene.camera["elevation"],
            "shown": shown,
        }))
        """.replace("json.dumps", "__import__('json').dumps"),
        """
        viewer.update(camera={"azimuth": 10.0}, lighting={"model": "shadows"})
        await settle(viewer)
        print(__import__('json').dumps({"panel": viewer._model.value,
                                        "az": viewer.scene.camera["azimuth"],
                                        "snap": list(viewer.snapshot().shape)}))
        """,
    ], tmp_path)
    drag = json.loads(_output(nb, 2))
    assert drag["first_shape"] == [96, 96, 3] and drag["after_shape"] == [96, 96, 3]
    # The snapshot's frame: not sent before a view was visible, sent once one was.
    assert drag["shown"][0] == 0 and drag["shown"][1] >= 1 and drag["shown"][2], drag
    # Frames arrived before the drag and during it (several reduced ones, then a full).
    assert drag["sent"][0] >= 1 and drag["sent"][1] - drag["sent"][0] >= 3, drag
    assert drag["diff"] > 1.0, drag
    # 38 px right (40 to 78) at 0.5 degrees per pixel: azimuth 19 degrees less.
    assert abs((drag["az"][0] - drag["az"][1]) % 360.0 - 19.0) < 1e-6, drag
    assert abs(drag["elevation"] - 2.0) < 1e-6, drag
    after = json.loads(_output(nb, 3))
    # A change made in Python shows in the panel and the scene.
    assert after == {"panel": "shadows", "az": 10.0, "snap": [96, 96, 3]}
    ran("notebook viewer in a kernel (nbclient)")


# A viewer busy refining a large `path` frame, as a widget on screen keeps it (every
# frame acknowledged at once by a task standing in for the browser).
BUSY_VIEWER = '''
import asyncio, time, glint
viewer = glint.Viewer({path!r}, size=(1024, 1024), lighting={{"model": "path", "spp": 1024}})
canvas = viewer.canvas
canvas._has_visible_views = True

async def browser():
    while True:
        canvas._frame_feedback = {{"index": canvas._rfb_frame_index,
                                   "timestamp": time.time(), "localtime": time.time()}}
        await asyncio.sleep(0.01)

task = asyncio.ensure_future(browser())
canvas.request_draw()
print("viewer")
'''


def _stopped_message_sent(kc, wait=3.0):
    """Whether the IOPub messages already sent (before the kernel's restart) hold
    a widget state update with the viewer's "kernel stopped" text."""
    from glint.notebook import STOPPED

    end = time.monotonic() + wait
    while time.monotonic() < end:
        try:
            msg = kc.get_iopub_msg(timeout=0.2)
        except queue.Empty:
            continue
        if msg["msg_type"] != "comm_msg":
            continue
        state = msg["content"].get("data", {}).get("state", {})
        if state.get("value") == STOPPED:
            return True
    return False


def test_kernel_restart_with_a_viewer_open(mni_path):
    """A kernel restart (and a shutdown) while a viewer renders: the kernel stops by
    itself, without jupyter_client's SIGTERM (sent half-way through its 5 s wait) or
    SIGKILL, and the new kernel answers and makes a viewer again. Every wait bounded."""
    _modules()
    from jupyter_client import KernelManager

    km = KernelManager(kernel_name="python3")
    km.start_kernel()
    kc = km.client()
    kc.start_channels()

    def run(code, timeout=60):
        """Runs code in the kernel; its stdout (an error fails the test)."""
        msg_id = kc.execute(code)
        out = []
        end = time.monotonic() + timeout
        while True:
            msg = kc.get_iopub_msg(timeout=max(0.1, end - time.monotonic()))
            if msg["parent_header"].get("msg_id") != msg_id:
                continue
            kind, content = msg["msg_type"], msg["content"]
            if kind == "stream":
                out.append(content["text"])
            elif kind == "error":
                pytest.fail(f"{content['ename']}: {content['evalue']}")
            elif kind == "status" and content["execution_state"] == "idle":
                return "".join(out)

    try:
        kc.wait_for_ready(timeout=60)
        assert run(BUSY_VIEWER.format(path=str(mni_path))) == "viewer\n"
        # The first frame renders now, on the kernel's event loop.
        time.sleep(0.5)
        old = km.provisioner.process
        km.restart_kernel(now=False)
        # Exited by itself (0), not terminated (-15) or killed (-9).
        assert old.returncode == 0, f"the kernel ended with {old.returncode}"
        # Before it exited, it told the page, in the viewer's panel (a widget state
        # update on IOPub), that the view no longer responds.
        assert _stopped_message_sent(kc), "no 'kernel stopped' message reached the page"
        kc.wait_for_ready(timeout=60)
        code = f"import glint\nprint(glint.Viewer({str(mni_path)!r}, size=(16, 16)).snapshot().shape)"
        assert run(code) == "(16, 16, 3)\n"
        # A shutdown with a busy viewer: the same.
        assert run(BUSY_VIEWER.format(path=str(mni_path))) == "viewer\n"
        time.sleep(0.5)
        old = km.provisioner.process
        km.shutdown_kernel(now=False)
        assert old.returncode == 0, f"the kernel ended with {old.returncode}"
    finally:
        kc.stop_channels()
        if km.has_kernel:
            km.shutdown_kernel(now=True)
    ran("notebook viewer: kernel restart (jupyter_client)")


def test_viewer_refines_path_frames_while_the_mouse_rests(mni_path):
    _modules()
    import glint

    v = glint.Viewer(str(mni_path), size=(32, 32), lighting={"model": "path", "spp": 4})
    samples = []
    while (f := v._session.next_frame()) is not None:
        samples.append((f[1], f[2], f[0].shape))
    # glint view's schedule: 1, 2, 4 samples, full size.
    assert samples == [("full", n, (32, 32, 3)) for n in (1, 2, 4)]
    v._session.update({"camera": {"azimuth": 30}}, True)
    f = v._session.next_frame()
    # A drag frame: path-traced at one sample, denoised, half size (issue 41).
    assert (f[1], f[2], f[0].shape) == ("interactive", 1, (16, 16, 3))
    assert v._session.next_frame() is None  # the full frame waits for the settle time
    assert v._session.settle_in() is not None
    snap = v.snapshot()
    assert snap.shape == (32, 32, 3)


def test_viewer_close_ends_its_session(mni_path):
    _modules()
    import glint

    v = glint.Viewer(str(mni_path), size=(16, 16), lighting={"model": "path", "spp": 64})
    shown = v.snapshot()
    assert v._session.pending()  # a path scene refining
    v.close()
    assert v._session.closed and not v._session.pending()
    assert v._frame() is None and v._session.next_frame() is None
    # The last frame still reads; a change is taken but nothing more is rendered.
    assert np.array_equal(v.snapshot(), shown)
    v.update(camera={"azimuth": 40})
    assert v._session.next_frame() is None and v.scene.camera["azimuth"] == 40


def test_viewer_bad_input_is_one_clear_message(tmp_path, mni_path):
    _modules()
    import glint

    missing = tmp_path / "nope.nii.gz"
    with pytest.raises(FileNotFoundError) as e:
        glint.Viewer(str(missing))
    assert str(missing) in str(e.value) and "\n" not in str(e.value)
    v = glint.Viewer(str(mni_path), size=(16, 16))
    before = v.scene
    with pytest.raises(ValueError) as e:
        v.update(colour="red")
    assert "colour" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(ValueError, match="input"):
        v.scene = {"input": "/etc/passwd"}
    assert v.scene == before


def test_viewer_shows_labels(tmp_path):
    _modules()
    import glint

    data = np.zeros((12, 12, 12), np.float32)
    data[3:9, 3:9, 3:9] = 100.0
    lab = np.zeros((12, 12, 12), np.int16)
    lab[3:6, 3:9, 3:9] = 1
    lab[6:9, 3:9, 3:9] = 2
    nib = require_module("nibabel")
    nib.save(nib.Nifti1Image(data, np.eye(4)), tmp_path / "v.nii.gz")
    nib.save(nib.Nifti1Image(lab, np.eye(4)), tmp_path / "l.nii.gz")
    v = glint.Viewer(str(tmp_path / "v.nii.gz"), size=(24, 24),
                     labels={"path": str(tmp_path / "l.nii.gz")})
    assert [l["value"] for l in v.labels] == [1, 2]
    shown = v.snapshot()
    v.update(labels={"hide": [str(l["value"]) for l in v.labels]})
    assert not np.array_equal(shown, v.snapshot())


def test_docs_notebook_runs(tmp_path, mni_path):
    """docs/notebook.ipynb, outputs stripped in the repository, runs in a kernel."""
    nbclient, nbformat = _modules()
    nb = nbformat.read(DOCS / "notebook.ipynb", as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert not cell.outputs and cell.execution_count is None, "outputs not stripped"
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    assert (tmp_path / "snapshot.png").is_file()
    ran("docs/notebook.ipynb (nbclient)")
