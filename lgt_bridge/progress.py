"""Progress bars for long runs (tqdm, imported only when a bar is actually shown).

``progress`` everywhere takes the same values:

* ``None`` (default): show a bar only when the run is long (more than ``DELAY`` s of
  wall time so far), stderr is a terminal, and the environment variable ``CI`` is not
  set: piped output and CI logs stay clean;
* ``True``: always show it (also when piped); ``False``: never.

The per-step cost is one increment and one comparison: the clock is read only every
``stride`` steps, with the stride adapted so that checks happen about every
``CHECK_S`` seconds.
"""
import os
import sys
import time

DELAY = 1.0          # s of wall time before a bar appears in the default mode
CHECK_S = 0.1        # s between two looks at the clock
_MAX_STRIDE = 4096


def mode(progress, stream=None):
    """"on", "auto" or None (off) for a ``progress`` argument."""
    if progress is None:
        stream = sys.stderr if stream is None else stream
        try:
            tty = stream.isatty()
        except (AttributeError, ValueError):
            return None
        return "auto" if tty and not os.environ.get("CI") else None
    return "on" if progress else None


class Progress:
    """A bar over ``total`` (simulated seconds, runs, ...) fed by ``state()``, which
    returns ``(done, postfix)`` and is called only when the bar is redrawn.

    Call :meth:`step` once per unit of work (cheap) and :meth:`close` at the end."""

    def __init__(self, progress, total, state, *, desc="", unit="", value_fmt=".4g", stream=None):
        self.mode = mode(progress, stream)
        self.total, self.state, self.desc, self.unit = total, state, desc, unit
        self.value_fmt = value_fmt
        self.stream = stream
        self.bar = None
        self._k = 0
        self._next = 1
        self._k_last = 0
        self.start = self._t_last = time.perf_counter()
        if self.mode is None:
            self.step = _nothing

    @property
    def shown(self):
        return self.bar is not None

    def step(self):
        self._k += 1
        if self._k >= self._next:
            self._check()

    def _check(self, force=False):
        now = time.perf_counter()
        dt, dk = now - self._t_last, self._k - self._k_last
        stride = int(dk * CHECK_S / dt) if dt > 0 else 2 * max(dk, 1)
        self._next = self._k + min(max(stride, 1), _MAX_STRIDE)
        self._t_last, self._k_last = now, self._k
        if self.bar is None:
            if self.mode == "auto" and not force and now - self.start < DELAY:
                return
            self._open()
        done, post = self.state()
        self.bar.n = min(done, self.total)
        self.bar.set_postfix_str(post, refresh=False)
        self.bar.refresh()

    def _open(self):
        from tqdm import tqdm
        fmt = self.value_fmt
        self.bar = tqdm(total=self.total, desc=self.desc, file=self.stream or sys.stderr, leave=True,
                        dynamic_ncols=True, mininterval=CHECK_S,
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:" + fmt + "}/{total:" + fmt + "}"
                                   + self.unit + " [{elapsed}<{remaining}{postfix}]")
        # elapsed and rate count from the run's start (tqdm's clock is time.time)
        self.bar.start_t = self.bar._time() - (time.perf_counter() - self.start)

    def close(self):
        """Final redraw and close (a bar in the default mode that never appeared stays away).
        The bar lets go of ``state`` (a closure that may refer to the bar and the run: no
        reference cycle outlives the run)."""
        if self.mode is None or self.state is None:       # (None: closed already)
            self.state = None
            return
        if self.bar is None and self.mode == "on":
            self._open()
        if self.bar is not None:
            self._check(force=True)
            self.bar.close()
        self.state = None


def _nothing():
    pass


#: the bar of every run that shows none (its step and close do nothing)
_OFF = None


def simulation_bar(progress, t0, t1, driver, stepper, desc="simulate"):
    """The bar of one integration: simulated time, steps, f evaluations, step size, rate."""
    global _OFF
    if mode(progress) is None:                 # no bar: one shared object that does nothing
        if _OFF is None:
            _OFF = Progress(False, 1.0, None)
        return _OFF

    def state():
        n = driver.n_steps
        el = time.perf_counter() - bar.start
        rate = f"{n / el:.3g} steps/s" if el > 0 else ""
        h = driver.h if driver.h is not None else float("nan")
        return (driver.t - t0,
                f"t={driver.t:.6g} s, steps={n}, f evals={stepper.prob.n_f}, h={h:.2e}, {rate}")
    bar = Progress(progress, t1 - t0, state, desc=desc, unit=" s")

    def tick(t, q, V):
        bar.step()
    # an on_step hook for the bar alone: it redraws from the driver's state, so it may be
    # called once per STRIDE steps (the compiled step loop then hands back only that often)
    tick.stride = STRIDE
    bar.hook = tick
    return bar


#: steps per call of a simulation bar's ``hook`` at most (a divisor of the simulation's
#: budget window, 1000 steps)
STRIDE = 50
