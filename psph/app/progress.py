"""Rank-0 progress: a bar (physical time, steps/s, ETA) on a terminal, else a log line every
few seconds. Never decides anything: it only reads the clock and prints."""

import sys
import time


class Progress:
    def __init__(self, end_time: float, enabled: bool, log_every: float = 5.0,
                 start_time: float = 0.0):
        self.end = end_time
        self.t0 = start_time
        self.enabled = enabled
        self.tty = enabled and sys.stderr.isatty()
        self.log_every = log_every
        self.start = time.perf_counter()
        self.last = self.start
        self.last_step = 0
        self.bar = None
        if self.tty:
            from tqdm import tqdm

            self.bar = tqdm(total=end_time, initial=start_time, unit="s", unit_scale=False,
                            file=sys.stderr,
                            bar_format="{l_bar}{bar}| t={n:.4g}/{total:.4g} s "
                                       "[{elapsed}<{remaining}] {postfix}")

    def update(self, t: float, step: int) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if self.tty:
            if now - self.last < 0.2:
                return
            rate = (step - self.last_step) / max(now - self.last, 1e-9)
            self.bar.n = min(t, self.end)
            self.bar.set_postfix_str(f"{rate:,.0f} steps/s", refresh=False)
            self.bar.refresh()
        elif now - self.last >= self.log_every:
            rate = (step - self.last_step) / (now - self.last)
            frac = t / self.end if self.end > 0 else 1.0
            done = (t - self.t0) / (self.end - self.t0) if self.end > self.t0 else 1.0
            el = now - self.start
            eta = el * (1 - done) / done if done > 0 else float("nan")
            print(f"[psph] t = {t:.5g}/{self.end:.5g} s ({100 * frac:.1f} %), step {step}, "
                  f"{rate:,.0f} steps/s, elapsed {el:.0f} s, ETA {eta:.0f} s", flush=True)
        else:
            return
        self.last = now
        self.last_step = step

    def close(self) -> None:
        if self.bar is not None:
            self.bar.n = self.end
            self.bar.refresh()
            self.bar.close()
