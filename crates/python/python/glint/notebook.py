"""``glint.Viewer``: an interactive view of a volume inside a Jupyter notebook.

The kernel renders; the browser only shows frames. The canvas is a ``jupyter_rfb``
remote frame buffer (an anywidget: no front-end extension to install, no second
port), the panel is made of ipywidgets. ``pip install glint[notebook]`` installs both.

Which frame is rendered when is not decided here: ``glint._glint.ViewSession`` is
``glint view``'s session (crates/view ``Session`` and its ``Schedule``), so the
notebook follows the browser viewer's rules exactly: while the mouse drags, reduced
frames (half size, a ``path`` scene in ``local`` light); once the input has been
quiet for ``settle`` seconds, a full frame; a ``path`` scene then refines, each frame
adding samples (1, 2, 4, 8, then 8 at a time) up to its ``spp``, while the mouse
rests. This module carries events in and frames out.

A kernel asked to shut down or restart while a viewer renders a ``path`` frame (seconds
at full size) would stop only once that frame is done: the render runs on the kernel's
main thread, and jupyter_client sends SIGTERM half-way through its 5 s wait. So every
viewer's session is closed as soon as the kernel is told to stop (IPython's
``exit_now``, set by the kernel's shutdown handler on its control thread): the frame in
flight is cancelled and the kernel exits by itself.
"""

from __future__ import annotations

import asyncio
import math
import time
import weakref

import numpy as np

from glint._glint import Scene, ViewSession, view_choices

try:
    import ipywidgets as _w
    from jupyter_rfb import RemoteFrameBuffer as _RFB
except ImportError as e:  # pragma: no cover - the message is the point
    raise ImportError(
        "glint.Viewer needs the notebook extra: pip install 'glint[notebook]' "
        f"(jupyter_rfb and ipywidgets; {e})"
    ) from None

#: Degrees the camera turns per pixel dragged (as ``glint view``'s page).
DEGREES_PER_PIXEL = 0.5
#: Seconds of quiet after a drag before the full frame (``glint view``'s 150 ms).
SETTLE = 0.15

#: What a viewer's panel says once its kernel is told to stop (a restart, a shutdown,
#: ``exit``): its frame stays, but nothing answers the mouse.
STOPPED = "The kernel stopped: this view no longer responds. Run its cell again."

# The live viewers, closed when the kernel is told to stop (_close_on_exit).
_LIVE: "weakref.WeakSet[Viewer]" = weakref.WeakSet()
_WATCHING: list = []


def _close_all(change):
    """IPython's ``exit_now`` became true (the kernel's shutdown or restart handler,
    on its control thread, or ``exit`` in a cell): every viewer's session is closed,
    cancelling a frame the main thread renders now."""
    if change.get("new"):
        for viewer in list(_LIVE):
            viewer._session.close()
            # The one message the page shows: the widget stays with its last frame
            # but no kernel answers it any more.
            viewer._status.value = STOPPED


def _close_on_exit(viewer):
    """Registers ``viewer`` for :func:`_close_all` (watching the shell once)."""
    _LIVE.add(viewer)
    if _WATCHING:
        return
    try:
        from IPython import get_ipython
    except ImportError:  # pragma: no cover - ipywidgets needs IPython
        return
    shell = get_ipython()
    if shell is not None and shell.has_trait("exit_now"):
        shell.observe(_close_all, names="exit_now")
        _WATCHING.append(shell)


class _Canvas(_RFB):
    """The frame buffer: mouse events to the viewer, frames from its session."""

    def __init__(self, viewer, **kwargs):
        super().__init__(**kwargs)
        self._viewer = viewer
        self.observe(self._on_visible, names="_has_visible_views")

    def _on_visible(self, change):
        if change["new"]:
            self._viewer._view_shown()

    def handle_event(self, event):
        self._viewer._event(event)

    def get_frame(self):
        return self._viewer._frame()


class Viewer(_w.HBox):
    """An inline, interactive view of a volume (a ``glint.Volume`` or a path).

    ``Viewer(volume_or_path, scene=None, size=(512, 512), **fields)``: ``scene`` a
    ``glint.Scene`` (its ``input`` replaced by the volume), keyword arguments replace
    its fields as in ``glint.Scene``; a ``labels`` label map and ``meshes`` are shown
    as ``glint view`` shows them. Drag to orbit, wheel to zoom; the panel chooses the
    preset, lighting model, lobe and light.

    ``viewer.scene`` is the live scene (a drag shows in ``viewer.scene.camera``);
    ``viewer.scene = {...}`` or ``viewer.update(**fields)`` patch it (the panel and
    the image follow); ``viewer.snapshot()`` is the frame shown, a numpy array.
    """

    def __init__(self, volume=None, scene=None, size=(512, 512), settle=SETTLE, **fields):
        base = scene if scene is not None else Scene()
        if not isinstance(base, Scene):
            raise TypeError(f"scene must be a glint.Scene, got {type(base).__name__}")
        w, h = (int(x) for x in size)
        base = base.replace(size=(w, h), **fields)
        # Reads the volume (and meshes, label map) first: a bad path raises here,
        # before any widget exists.
        self._session = ViewSession(volume, base, float(settle))
        self._last = None
        self._drag = None
        self._settle_handle = None
        # Pacing of drag frames: a pause of a quarter of the last one's render time.
        self._pace_handle = None
        self._next_draw_at = 0.0
        self._frames = 0
        # The last frame is to be sent again (a view appeared that may not have it).
        self._resend = False
        self._syncing = False
        self.canvas = _Canvas(
            self,
            css_width=f"{w}px",
            css_height=f"{h}px",
            resizable=False,
            quality=80,
        )
        self.panel = self._make_panel()
        super().__init__([self.canvas, self.panel])
        self._show_scene()
        _close_on_exit(self)
        self.canvas.request_draw()

    def close(self):
        """Closes the widget and ends its session: a frame in flight is cancelled
        and no more are rendered (``snapshot()`` then returns the last frame)."""
        if not hasattr(self, "_session"):
            # The constructor raised (a bad path) before the session existed; the
            # widget's finaliser still calls this.
            super().close()
            return
        self._session.close()
        for handle in (self._settle_handle, self._pace_handle):
            if handle is not None:
                handle.cancel()
        self._settle_handle = self._pace_handle = None
        _LIVE.discard(self)
        self.canvas.close()
        super().close()

    # -- the live scene ----------------------------------------------------------

    @property
    def scene(self) -> Scene:
        """The live scene (resolved: every default chosen)."""
        return self._session.scene

    @scene.setter
    def scene(self, value):
        if isinstance(value, Scene):
            value = value.to_dict()
            for fixed in ("input", "meshes", "version", "derived"):
                value.pop(fixed, None)
        if not isinstance(value, dict):
            raise TypeError(
                f"viewer.scene takes a glint.Scene or a dict of fields, got {type(value).__name__}"
            )
        self.update(**value)

    def update(self, **fields):
        """Patches the live scene (``camera``, ``lobe``, ``material``, ``lighting`` merge
        field by field; others replace): the panel and the image follow. An unknown
        field or a bad value raises ValueError and changes nothing."""
        self._session.update(fields, False)
        self._show_scene()
        self.canvas.request_draw()

    @property
    def labels(self):
        """The labels of the scene's label map (dicts of value, name, color, voxels)."""
        return self._session.labels()

    @property
    def frames(self) -> int:
        """Frames rendered so far."""
        return self._frames

    def snapshot(self) -> np.ndarray:
        """The frame shown now, an sRGB uint8 array (height, width, 3): a frame still
        owed (a change not yet drawn, a drag's full frame) is rendered first, at full
        size, and shown in the widget too."""
        if self._session.closed:
            if self._last is None:
                raise RuntimeError("this glint.Viewer is closed and never showed a frame")
            return np.array(self._last[0])
        drawn = False
        while True:
            frame = self._session.next_frame()
            if frame is None:
                break
            self._shown(frame)
            drawn = True
            if frame[1] != "interactive":
                break
        if self._last is None or self._last[1] == "interactive":
            # A drag not yet settled: its full frame now.
            self._session.update({}, False)
            frame = self._session.next_frame()
            if frame is not None:  # None: closed meanwhile (the kernel stopping)
                self._shown(frame)
                drawn = True
        if drawn:
            self._send(self._last[0])
        if self._last is None:
            raise RuntimeError("this glint.Viewer was closed before its first frame")
        return np.array(self._last[0])

    def _send(self, array):
        """Shows a frame rendered outside the widget's draw (a snapshot): sent now
        when a view shows the widget, else when one appears (:meth:`_view_shown`)."""
        if self.canvas.comm is not None and self.canvas._has_visible_views:
            self.canvas.send_frame(array)
        else:
            self._resend = True

    def _view_shown(self):
        """A view of the canvas became visible: it gets the last frame, even when
        no new one is owed. Without this, a notebook run with Run All left the
        canvas grey: the snapshot cell took the frame owed and sent it before the
        browser's view existed (a frame that reaches the page before the widget's
        script has loaded is lost, and a view starts as a grey pixel), so the draw
        asked for when the view appeared had nothing new to send."""
        if self._last is not None:
            self._resend = True
        self.canvas.request_draw()

    # -- events and frames ---------------------------------------------------------

    def _event(self, event):
        kind = event.get("event_type") or event.get("type")
        if kind == "pointer_down" and event.get("button", 1) == 1:
            self._drag = (event["x"], event["y"])
        elif kind == "pointer_move" and self._drag is not None:
            x, y = event["x"], event["y"]
            dx, dy = x - self._drag[0], y - self._drag[1]
            self._drag = (x, y)
            cam = self.scene.camera
            az = (cam["azimuth"] - dx * DEGREES_PER_PIXEL) % 360.0
            el = max(-89.0, min(89.0, cam["elevation"] + dy * DEGREES_PER_PIXEL))
            self._interact({"camera": {"azimuth": az, "elevation": el}})
        elif kind == "pointer_up":
            self._drag = None
        elif kind == "wheel":
            zoom = self.scene.camera["zoom"] * math.pow(1.1, -event.get("dy", 0.0) / 100.0)
            self._interact({"camera": {"zoom": max(0.2, min(20.0, zoom))}})

    def _interact(self, patch):
        self._session.update(patch, True)
        self._request_paced()
        # The full frame once the input settles: ask for a draw then (the session
        # decides whether it is due).
        wait = self._session.settle_in()
        if wait is not None:
            self._later(wait + 0.005)

    def _request_paced(self):
        """Asks for a drag frame, after a pause of a quarter of the last drag frame's
        render time (at least 5 ms). The kernel takes the events that arrived meanwhile
        (each only patches the scene, microseconds) and the next frame shows the
        latest of them: without the pause, a frame slower than the events drew once
        per event and the events queued up behind the frames (seconds of lag within a
        few seconds of dragging; scripts/bench/bench-notebook-drag).
        """
        wait = self._next_draw_at - time.perf_counter()
        if wait <= 0:
            self.canvas.request_draw()
            return
        if self._pace_handle is not None:
            return
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:
            self.canvas.request_draw()
            return
        self._pace_handle = loop.call_later(wait, self._paced)

    def _paced(self):
        self._pace_handle = None
        self.canvas.request_draw()

    def _later(self, seconds):
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:
            return
        if self._settle_handle is not None:
            self._settle_handle.cancel()
        self._settle_handle = loop.call_later(seconds, self._settled)

    def _settled(self):
        self._settle_handle = None
        wait = self._session.settle_in()
        if wait is not None and wait > 0:
            self._later(wait + 0.005)
        else:
            self.canvas.request_draw()

    def _frame(self):
        if self._session.closed:
            return None
        started = time.perf_counter()
        frame = self._session.next_frame()
        if frame is None:
            if self._resend and self._last is not None:
                self._resend = False
                return self._last[0]
            return None
        self._resend = False
        if frame[1] == "interactive":
            ended = time.perf_counter()
            self._next_draw_at = ended + max(0.005, (ended - started) / 4)
        self._shown(frame)
        # A `path` scene still refining owes the next frame: asked for after this one
        # is sent, so input that arrives meanwhile is handled first.
        if self._session.pending() and self._session.settle_in() is None:
            try:
                asyncio.get_running_loop().call_soon(self.canvas.request_draw)
            except RuntimeError:
                pass
        return frame[0]

    def _shown(self, frame):
        self._last = frame
        self._frames += 1
        if frame[1] != "interactive":
            self._show_scene()

    # -- the panel -------------------------------------------------------------------

    def _make_panel(self):
        choices = view_choices()
        self._preset = _w.Dropdown(options=[""] + list(choices["presets"]), description="preset")
        self._model = _w.Dropdown(options=list(choices["lighting"]), description="lighting")
        self._lobe = _w.Dropdown(options=list(choices["lobes"]), description="lobe")
        self._light_az = _w.FloatSlider(min=-90, max=90, step=1, description="light az")
        self._light_el = _w.FloatSlider(min=-90, max=90, step=1, description="light el")
        self._status = _w.Label("")
        self._preset.observe(self._on_preset, names="value")
        self._model.observe(self._on_model, names="value")
        self._lobe.observe(self._on_lobe, names="value")
        self._light_az.observe(self._on_light, names="value")
        self._light_el.observe(self._on_light, names="value")
        box = [self._preset, self._model, self._lobe, self._light_az, self._light_el, self._status]
        return _w.VBox(box, layout=_w.Layout(width="320px"))

    def _show_scene(self):
        """The panel shows the live scene (without sending its changes back)."""
        s = self.scene
        lighting = s.lighting or {"model": "local"}
        lights = s.lights or [{"azimuth": 0.0, "elevation": 0.0}]
        self._syncing = True
        try:
            self._preset.value = s.preset or ""
            self._model.value = lighting["model"]
            self._lobe.value = s.lobe["kind"]
            self._light_az.value = float(lights[0].get("azimuth", 0.0))
            self._light_el.value = float(lights[0].get("elevation", 0.0))
            samples = f", {self._last[2]} spp" if self._last and self._last[2] else ""
            self._status.value = f"{s.size[0]}x{s.size[1]} {lighting['model']}{samples}"
        finally:
            self._syncing = False

    def _from_panel(self, **fields):
        if self._syncing:
            return
        try:
            self.update(**fields)
        except ValueError as e:
            self._status.value = str(e)

    def _on_preset(self, change):
        if change["new"]:
            self._from_panel(preset=change["new"])

    def _on_model(self, change):
        patch = {
            "model": change["new"],
            "spp": None,
            "bounces": None,
            "seed": None,
            "environment": None,
            "anisotropy": None,
            "occlusion": None,
            "sampler": None,
            "time_budget": None,
            "show_environment": None,
        }
        self._from_panel(lighting=patch)

    def _on_lobe(self, change):
        self._from_panel(lobe={"kind": change["new"]})

    def _on_light(self, change):
        light = {"azimuth": self._light_az.value, "elevation": self._light_el.value, "intensity": 1.0}
        self._from_panel(lights=[light])
