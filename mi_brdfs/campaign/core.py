"""Campaign plumbing: the context sections receive, sections, summary rows, the report."""

from __future__ import annotations

import contextlib
import datetime
import os
import platform
import re
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from ..checks.result import CheckResult
from ..errors import MiBrdfsError, MiBrdfsWarning
from ..markdown import md_table  # noqa: F401 (the sections import it from here)
from ..progress import Progress


#: What a quick run names in place of a figure it leaves unmeasured: a quick bench measures the
#: first pair, material or choice of a table alone, since each contender is a kernel to compile.
SKIPPED = "— (quick run)"


@dataclass
class Context:
    """What every section gets: where to write, how thorough to be, the variants."""

    out: Path                  # the report's folder (REPORT.md, figures/)
    quick: bool = False        # CI-sized: fewer samples, fewer parameters, smaller images
    variant: str = "llvm_ad_rgb"
    scalar_variant: str = "scalar_rgb"

    @property
    def figures(self) -> Path:
        return self.out / "figures"

    def figure(self, name: str) -> Path:
        """Path of a figure file (created folder); Markdown refers to it relatively."""
        self.figures.mkdir(parents=True, exist_ok=True)
        return self.figures / name

    def n(self, full: int, quick: int) -> int:
        return quick if self.quick else full

    @contextlib.contextmanager
    def scalar(self, threads: int | None = None):
        """
        Within: the scalar variant, on ``threads`` render threads where given (a section
        may set others); after: :attr:`variant` and the thread count there was before.
        """
        import drjit as dr

        from ..registry import use_variant
        use_variant(self.scalar_variant)
        before = dr.thread_count()
        try:
            if threads is not None:
                dr.set_thread_count(threads)
            yield
        finally:
            dr.set_thread_count(before)
            use_variant(self.variant)


@dataclass
class Row:
    """One line of the report's summary table."""

    plugin: str
    check: str
    result: str
    tolerance: str
    passed: bool
    expected_fail: bool = False   # a lecture form that must fail (e.g. energy of 'lecture')
    judged: bool = True           # False: a quick run's measurement, too short to judge

    @classmethod
    def of(cls, plugin: str, result: CheckResult, check: str | None = None,
           expected_fail: bool = False) -> "Row":
        return cls(plugin, check or result.name, _fmt(result.value), _fmt(result.tolerance),
                   result.passed, expected_fail)

    @property
    def verdict(self) -> str:
        if not self.judged:
            return "not judged (quick run)"
        if self.expected_fail:
            return "fails, as expected" if not self.passed else "**passes (expected to fail)**"
        return "pass" if self.passed else "**FAIL**"

    @property
    def ok(self) -> bool:
        return not self.judged or self.passed != self.expected_fail


@dataclass
class Section:
    """A topic of the report."""

    title: str
    markdown: str = ""
    rows: list = field(default_factory=list)
    seconds: float = 0.0
    #: Named figures, formatted as the report prints them, for documents that quote the report
    #: (:func:`fill_quotes`).
    values: dict = field(default_factory=dict)


def _fmt(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def image(ctx: Context, path: Path, alt: str) -> str:
    return f"![{alt}]({os.path.relpath(path, ctx.out)})"


def run(sections, ctx: Context, progress: bool = True, title: str = "mi_brdfs validation report",
        filename: str = "REPORT.md", command: str = "mi-brdfs validate",
        make_target: str = "make validate", what: str = "checks",
        quick_note: str = "fewer samples and parameters",
        judge_quick: bool = True) -> tuple[Path, list[Section], dict]:
    """
    Run the sections in order and write the report; returns its path, the sections and the
    named figures of them all (:attr:`Section.values`, with the run's ``run: minutes`` and
    ``run: as expected``). With ``judge_quick`` false, a quick run's rows get no verdict (its
    timings are too short to mean anything).
    """
    import drjit as dr
    import mitsuba as mi

    from .._version import __version__
    from ..registry import use_variant

    ctx.out.mkdir(parents=True, exist_ok=True)
    done: list[Section] = []
    bar = Progress(len(sections), label=filename, unit=" sections") if progress else None
    start = time.perf_counter()
    for i, make in enumerate(sections):
        t0 = time.perf_counter()
        use_variant(ctx.variant)
        section = _section(make, ctx)
        section.seconds = time.perf_counter() - t0
        done.append(section)
        if bar:
            bar.update(i + 1, note=section.title[:40])
    if bar:
        bar.close()
    total = time.perf_counter() - start
    rows = [r for s in done for r in s.rows]
    judged = not ctx.quick or judge_quick
    for r in rows:
        r.judged = judged and r.judged  # (a section may leave a quick row unjudged)
    failed = [r for r in rows if not r.ok]
    command = command + (" --quick" if ctx.quick else "")
    head = [
        f"# {title}",
        "",
        f"Generated by `{command}` (also `{make_target}`) on "
        f"{datetime.date.today().isoformat()}: mi_brdfs {__version__}, Mitsuba "
        f"{mi.__version__}, drjit {dr.__version__}, {platform.machine()} with "
        f"{os.cpu_count()} cores, {total / 60:.1f} min"
        + (f" (**quick mode**: {quick_note})" if ctx.quick else "") + ".",
        "Every number below comes from that run; rerun the command to regenerate it all.",
        "",
        "## Summary",
        "",
        (f"{len(rows) - len(failed)} of {len(rows)} {what} behave as expected"
         + (f"; **{len(failed)} do not** (listed first below)." if failed else ".")) if judged
        else f"{len(rows)} {what} taken, none judged: {quick_note}.",
        "",
        md_table(["subject", what, "as expected", "expected to fail, and fail", "unexpected"],
                 _per_subject(rows)) if judged else "",
        "",
        f"<details><summary>all {len(rows)} {what}</summary>",
        "",
        md_table(["subject", "check", "result", "tolerance", "verdict"],
                 [(r.plugin, r.check, r.result if judged else "—", r.tolerance, r.verdict)
                  for r in sorted(rows, key=lambda r: r.ok)]),
        "",
        "</details>",
        "",
        "Contents: " + ", ".join(f"[{s.title}](#{_anchor(s.title)})" for s in done),
        "",
    ]
    body = []
    for s in done:
        body += [f"## {s.title}", "", s.markdown.strip(), "",
                 f"*Section time: {s.seconds:.0f} s.*", ""]
    report = ctx.out / filename
    from ..imageio import atomic_path
    with atomic_path(report, ".md") as tmp:
        Path(tmp).write_text("\n".join(head + body))
    values = {"run: minutes": f"{total / 60:.1f}",
              "run: as expected": f"{len(rows) - len(failed)} of {len(rows)}" if judged
              else "not judged"}
    for s in done:
        values.update(s.values)
    return report, done, values


def _section(make, ctx: Context) -> Section:
    """One section, made in this process. Parameter grids include deliberately energy-gaining
    sets: their warnings are noise. A Ctrl-C stops the report (KeyboardInterrupt), also where
    drjit wrapped it (:func:`_interrupted`)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)
        try:
            return make(ctx)
        except Exception as e:
            if _interrupted(e):
                raise KeyboardInterrupt from None
            raise


def _interrupted(error: BaseException) -> bool:
    """Whether a KeyboardInterrupt caused ``error``: a Ctrl-C while Mitsuba runs a Python
    plugin's method (a scalar render) reaches the caller as drjit's RuntimeError ("error while
    performing a custom differentiable operation") with the KeyboardInterrupt as its cause."""
    while error is not None:
        if isinstance(error, KeyboardInterrupt):
            return True
        error = error.__cause__ or error.__context__
    return False


def _per_subject(rows) -> list:
    """
    One summary line per subject: the first word of the row's plugin column, lower case, without
    punctuation or hyphens ('Cook-Torrance Smith, α = 0.2' and 'cooktorrance (smith)' are one).
    """
    subjects: dict[str, list] = {}
    for r in rows:
        word = re.split(r"[\s,(]", r.plugin.strip(), maxsplit=1)[0]
        subjects.setdefault(word.lower().replace("-", ""), []).append(r)
    return [(name, len(rs), sum(r.ok for r in rs),
             sum(r.expected_fail and not r.passed for r in rs),
             sum(not r.ok for r in rs) or "—") for name, rs in subjects.items()]


def _anchor(title: str) -> str:
    keep = [c.lower() if c.isalnum() else "-" if c in " -" else "" for c in title]
    return "".join(keep)


#: A quoted figure in a Markdown document: ``<!-- TAG: KEY -->VALUE<!-- /TAG -->``, on one line
#: (HTML comments do not show in rendered Markdown, in a table cell either).
_QUOTE = r"<!-- {tag}: ([^>]+?) -->(.*?)<!-- /{tag} -->"


def fill_quotes(path: Path, values: dict, tag: str) -> int:
    """
    Replace every quoted figure of ``tag`` in the Markdown file ``path`` by the value of its key
    in ``values``; returns how many there were. A key that ``values`` lacks is an error (naming
    every such key), and then the file is left as it was; it is rewritten atomically.
    """
    from ..imageio import atomic_path

    path = Path(path)
    text = path.read_text()
    pattern = re.compile(_QUOTE.format(tag=re.escape(tag)))
    keys = [m.group(1) for m in pattern.finditer(text)]
    unknown = sorted(set(keys) - set(values))
    if unknown:
        raise MiBrdfsError(f"{path}: quotes figures this run did not measure: "
                           f"{', '.join(repr(k) for k in unknown)}")
    filled = pattern.sub(lambda m: f"<!-- {tag}: {m.group(1)} -->{values[m.group(1)]}"
                                   f"<!-- /{tag} -->", text)
    with atomic_path(path, ".md") as tmp:
        Path(tmp).write_text(filled)
    return len(keys)
