"""The GIL is released while rendering, a render stops when asked (its progress callback,
Session.stop, Ctrl-C), and a stopped render is the render of the passes it made."""
import os
import signal
import threading

import numpy as np
import pytest

import trac0r


def wait_for_samples(session, n):
    """Runs Python in this thread until the other thread's render has made n passes."""
    loops = 0
    while session.progress.samples < n:
        loops += 1
        threading.Event().wait(0.001)
    return loops


def test_python_runs_while_rendering(cornell):
    """Without the GIL released, this thread could not poll the progress, nor stop the
    render (it asks for a million samples): the test would hang."""
    s = trac0r.Session(cornell, spp=1000000, seed=1)
    out = {}
    worker = threading.Thread(target=lambda: out.setdefault("p", s.run()))
    worker.start()
    wait_for_samples(s, 2)
    with pytest.raises(trac0r.InvalidOperationError):
        s.run()  # one run at a time
    with pytest.raises(trac0r.InvalidOperationError):
        cornell.camera = {"fov": 50}  # not while it renders
    s.stop()
    worker.join()
    p = out["p"]
    assert p.end == "cancelled" and 2 <= p.samples < 1000000
    # Going on after a stop renders the same image as one run of the same passes.
    more = s.run(samples=1)
    assert more.samples == p.samples + 1
    ref = trac0r.render(cornell, spp=more.samples, seed=1)
    assert np.array_equal(s.result().image, ref.image)
    s.close()


def test_concurrent_renders(cornell):
    results = [None, None]

    def work(k):
        results[k] = trac0r.render(cornell, spp=2, seed=k).image

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k in range(2):
        assert np.array_equal(results[k], trac0r.render(cornell, spp=2, seed=k).image)


def test_progress_callback_cancels(cornell):
    seen = []

    def progress(p):
        seen.append(p.samples)
        return p.samples >= 3  # stop after the third pass

    r = trac0r.render(cornell, spp=100, seed=9, progress=progress)
    assert r.end == "cancelled" and r.spp == 3 and seen == [1, 2, 3]
    assert np.array_equal(r.image, trac0r.render(cornell, spp=3, seed=9).image)


def test_progress_callback_exception(cornell):
    def progress(p):
        raise ZeroDivisionError("from the callback")

    with pytest.raises(ZeroDivisionError, match="from the callback"):
        trac0r.render(cornell, spp=100, progress=progress)
    r = trac0r.render(cornell, spp=1)  # the module still works
    assert r.spp == 1


def test_keyboard_interrupt_cancels(cornell):
    """SIGINT (Ctrl-C) during a render on the main thread: the next pass's end runs the
    handler, which raises KeyboardInterrupt out of the render."""
    assert threading.current_thread() is threading.main_thread()
    s = trac0r.Session(cornell, spp=1000000)

    def interrupt():
        wait_for_samples(s, 1)
        os.kill(os.getpid(), signal.SIGINT)

    t = threading.Thread(target=interrupt)
    t.start()
    with pytest.raises(KeyboardInterrupt):
        s.run()
    t.join()
    p = s.progress
    assert p.end == "cancelled" and 1 <= p.samples < 1000000
    s.close()
