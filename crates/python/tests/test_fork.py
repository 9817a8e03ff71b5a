"""A process that has rendered and then forks (multiprocessing's default start method on
Linux, Dask and pytest-xdist workers) renders in the child as in the parent."""

import multiprocessing
import os

import numpy as np

import glint


def _render_in_child(queue, scene):
    image = glint.render(None, scene)
    queue.put(image.tobytes())


def test_a_forked_child_renders_after_the_parent_did():
    scene = glint.Scene(input={"phantom": {"name": "shepp-logan", "size": 48}}, size=(64, 48))
    # The parent renders first: its thread pool exists when it forks.
    want = glint.render(None, scene)
    assert want.max() > 0
    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    child = ctx.Process(target=_render_in_child, args=(queue, scene))
    child.start()
    child.join(timeout=120)
    alive = child.is_alive()
    if alive:
        child.kill()
    assert not alive, "the forked child hung rendering"
    assert child.exitcode == 0
    got = np.frombuffer(queue.get(timeout=10), dtype=np.uint8).reshape(want.shape)
    assert np.array_equal(got, want)


def test_a_bare_fork_renders_too():
    scene = glint.Scene(input={"phantom": {"name": "head", "size": 40}}, size=(32, 32))
    want = glint.render(None, scene)
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: render, report, and leave without running the parent's cleanup
        try:
            ok = np.array_equal(glint.render(None, scene), want)
            os.write(write, b"1" if ok else b"0")
        finally:
            os._exit(0)
    os.close(write)
    # A child that hangs writes nothing: waitpid with a deadline via the pipe's read.
    import select
    ready, _, _ = select.select([read], [], [], 120)
    if not ready:
        os.kill(pid, 9)
    os.waitpid(pid, 0)
    assert ready, "the forked child hung rendering"
    assert os.read(read, 1) == b"1"
