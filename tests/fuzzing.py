"""Seeded mutation fuzzing for parsers: mutate valid inputs, feed each to a target, accept only clean errors.

A campaign takes a few valid inputs (the seeds), derives ``cases`` mutants from them with a seeded
random generator (bit flips, deletions, duplications, splices, truncation, and insertion of tokens
that broke parsers before: huge numbers, ``1e400``, ``nan``, deep nesting, NUL, invalid UTF-8), and
calls the target on each.  A case fails when the target raises anything but the allowed errors
(``PixelpenError`` by default), runs longer than ``seconds_per_case``, or allocates more than
``memory_mb`` (tracemalloc peak).  The default suite runs :data:`QUICK_CASES` cases per parser;
``pytest -m slow`` runs the :data:`SLOW_CASES` campaigns (:func:`depths` parametrizes a test for both).
"""

from __future__ import annotations

import random
import signal
import time
import traceback
import tracemalloc
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field

import pytest

from pixelpen.errors import PixelpenError

QUICK_CASES = 300
"""Cases per parser in the default suite."""
SLOW_CASES = 10_000
"""Cases per parser in the ``slow`` campaign."""

TOKENS: tuple[bytes, ...] = (
    b"1e400", b"-1e400", b"nan", b"NaN", b"inf", b"-inf", b"9" * 5000, b"-" + b"9" * 400, b"0x", b"\x00",
    b"\xff\xfe", b"\xc3\x28", b"\xb2", b"[" * 1000, b"{" * 1000, b"(" * 500, b"<g>" * 300, b",,,,", b";;;",
    b"1e-300", b"-0", b"4294967296", b"18446744073709551617", b"\r\n", b"\x1b.", b"\x03", b"%",
)
"""Byte strings inserted by the ``token`` mutation."""


def depths(quick_seed: int = 1, slow_seed: int = 2) -> pytest.MarkDecorator:
    """A campaign test parametrized by ``cases`` and ``seed``: :data:`QUICK_CASES` in the default suite,
    :data:`SLOW_CASES` under ``pytest -m slow``."""
    return pytest.mark.parametrize(("cases", "seed"), [
        pytest.param(QUICK_CASES, quick_seed, id="quick"),
        pytest.param(SLOW_CASES, slow_seed, id="slow", marks=pytest.mark.slow),
    ])


class _CaseTimeout(Exception):
    pass


@dataclass
class Failure:
    """One failing case: what went wrong and the input that did it."""

    kind: str  # "crash", "hang" or "memory"
    data: bytes
    detail: str

    def __str__(self) -> str:
        shown = self.data if len(self.data) <= 300 else self.data[:300] + b"..."
        return f"{self.kind}: {self.detail}\n  input ({len(self.data)} bytes): {shown!r}"


@dataclass
class CampaignResult:
    """Counts of a campaign: cases run, clean errors raised, failures with their inputs."""

    name: str
    cases: int = 0
    rejected: int = 0
    accepted: int = 0
    failures: list[Failure] = field(default_factory=list)
    seconds: float = 0.0
    peak_mb: float = 0.0

    def check(self) -> None:
        """Print the summary; fail the test with the first few failing inputs, if any."""
        print(self.summary())
        if self.failures:
            shown = "\n".join(str(f) for f in self.failures[:5])
            raise AssertionError(f"{self.name}: {len(self.failures)} of {self.cases} cases failed\n{shown}")

    def summary(self) -> str:
        """One line for reports: cases, accepted, rejected with clean errors, failures, time, peak memory."""
        return (f"{self.name}: {self.cases} cases, {self.accepted} accepted, {self.rejected} rejected cleanly, "
                f"{len(self.failures)} failures, {self.seconds:.1f} s, peak {self.peak_mb:.1f} MB")


def mutate(data: bytes, rng: random.Random, others: Sequence[bytes] = (), tokens: Sequence[bytes] = TOKENS) -> bytes:
    """One to four random mutations of ``data``."""
    out = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        op = rng.randrange(7)
        n = len(out)
        i = rng.randrange(n + 1)
        if op == 0 and n:  # flip a bit
            j = rng.randrange(n)
            out[j] ^= 1 << rng.randrange(8)
        elif op == 1 and n:  # delete a span
            out[i:i + rng.randint(1, 16)] = b""
        elif op == 2 and n:  # duplicate a span
            j = rng.randrange(n)
            out[i:i] = out[j:j + rng.randint(1, 64)] * rng.choice((1, 2, 8))
        elif op == 3:  # insert a known troublemaker
            out[i:i] = rng.choice(tokens)
        elif op == 4:  # random bytes
            out[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 8)))
        elif op == 5 and n:  # truncate
            del out[rng.randrange(n):]
        elif op == 6 and others:  # splice with another seed
            other = rng.choice(others)
            j = rng.randrange(len(other) + 1)
            out[i:] = other[j:]
    return bytes(out)


def mutants(seeds: Sequence[bytes], cases: int, seed: int, tokens: Sequence[bytes] = TOKENS) -> Iterator[bytes]:
    """``cases`` seeded mutants of the seeds (the seeds themselves first)."""
    rng = random.Random(seed)
    for k in range(cases):
        if k < len(seeds):
            yield seeds[k]
        else:
            yield mutate(rng.choice(seeds), rng, seeds, tokens)


def campaign(
    name: str,
    target: Callable[[bytes], object],
    seeds: Sequence[bytes],
    cases: int,
    *,
    seed: int = 0,
    allowed: tuple[type[BaseException], ...] = (PixelpenError,),
    tokens: Sequence[bytes] = TOKENS,
    seconds_per_case: float = 5.0,
    memory_mb: float = 256.0,
) -> CampaignResult:
    """Run ``cases`` mutants of ``seeds`` through ``target``; every outcome but success or an allowed error fails."""
    result = CampaignResult(name)
    use_alarm = hasattr(signal, "setitimer")

    def on_alarm(signum: int, frame: object) -> None:
        raise _CaseTimeout()

    old_handler = signal.signal(signal.SIGALRM, on_alarm) if use_alarm else None
    started_tracing = not tracemalloc.is_tracing()
    if started_tracing:
        tracemalloc.start()
    t0 = time.perf_counter()
    try:
        for data in mutants(seeds, cases, seed, tokens):
            result.cases += 1
            tracemalloc.reset_peak()
            base = tracemalloc.get_traced_memory()[0]
            if use_alarm:
                signal.setitimer(signal.ITIMER_REAL, seconds_per_case)
            try:
                target(data)
                result.accepted += 1
            except allowed:
                result.rejected += 1
            except _CaseTimeout:
                result.failures.append(Failure("hang", data, f"still running after {seconds_per_case} s"))
            except BaseException as exc:
                if isinstance(exc, KeyboardInterrupt):
                    raise
                tb = traceback.format_exception(type(exc), exc, exc.__traceback__)[-3:]
                result.failures.append(Failure("crash", data, "".join(tb).strip()))
            finally:
                if use_alarm:
                    signal.setitimer(signal.ITIMER_REAL, 0)
            peak_mb = (tracemalloc.get_traced_memory()[1] - base) / 2**20
            result.peak_mb = max(result.peak_mb, peak_mb)
            if peak_mb > memory_mb:
                result.failures.append(Failure("memory", data, f"allocated {peak_mb:.0f} MB (limit {memory_mb:.0f})"))
    finally:
        if started_tracing:
            tracemalloc.stop()
        if use_alarm:
            signal.signal(signal.SIGALRM, old_handler)
        result.seconds = time.perf_counter() - t0
    return result
