"""Sweep reports: [[plots]] checked at load time, reductions, results.h5, plots and index.html.

The promises (issue 14): a plot's paths are checked against the sweep's parameters when the file
is loaded, each problem with its line and a did-you-mean; reductions combine the runs sharing an
x and a series exactly as stated; results.h5 reads back to the table's values; the index page is
one file whose every link resolves, whose user text is escaped, and which loads in Chromium from
file:// with its plots; a figure that fails to draw never costs the results table; and the
shortened spring_stability example finds the largest stable step the lecture's theory predicts.
"""

from __future__ import annotations

import csv
import html.parser
import json
import math
import subprocess
import sys
import tomllib
from pathlib import Path
from urllib.parse import unquote, urlparse

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image
from playwright.sync_api import sync_playwright

import visviva as vv
from test_sweeps import GRID, InlineExecutor, spring_sweep, write
from test_viewer import CHROMIUM, CHROMIUM_FLAGS
from visviva.errors import ModelError, SweepError
from visviva.sweeps import Plot, SweepInterrupted, parse_sweep, read_results_h5
from visviva.sweeps.index_page import write_index
from visviva.sweeps.reductions import reduce_plot
from visviva.sweeps.reports import write_plot, write_reports
from visviva.sweeps.results_h5 import write_results_h5

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "sweeps"
#: Pixels of a plot's PNG: 7.5 × 5 inches at 110 per inch.
PLOT_SIZE = (825, 550)

PLOTTED = """
[[parameters]]
path = "entities[pair].stiffness"
values = [10.0, 100.0]
[[parameters]]
path = "integration.method"
values = ["explicit_euler", "rk4"]
[[parameters]]
path = "integration.dt"
values = [0.01, 0.02]
{plots}
"""


def plotted(plots: str) -> str:
    return spring_sweep(PLOTTED.format(plots=plots))


def refusal(text: str) -> str:
    with pytest.raises(SweepError) as caught:
        parse_sweep(text, source="s.toml")
    return str(caught.value)


def line_of(text: str, needle: str) -> int:
    """The line of the first ``needle`` from the first ``[[plots]]`` on."""
    lines = text.splitlines()
    start = lines.index("[[plots]]")
    return next(i for i, line in enumerate(lines[start:], start=start + 1) if needle in line)


# ---------------------------------------------------------------- the description


@pytest.mark.parametrize(
    ("plot", "where", "message"),
    [
        (
            'x = "entities[pair].stifness"\ny = "steps"\nreduce = "max"',
            "plots[0].x",
            "Did you mean 'entities[pair].stiffness'?",
        ),
        (
            'x = "integration.dt"\ny = "max_energy_eror"\nseries = "integration.method"\n'
            'reduce = "max"',
            "plots[0].y",
            "Did you mean 'max_energy_error'?",
        ),
        (
            'x = "integration.dt"\ny = "steps"\nseries = "integration.methd"\nreduce = "max"',
            "plots[0].series",
            "Did you mean 'integration.method'?",
        ),
        (
            'x = "world.gravity"\ny = "steps"\nreduce = "max"',
            "plots[0].x",
            "must be one of the sweep's parameter paths (got 'world.gravity')",
        ),
        (
            'x = "integration.dt"\ny = "steps"\nreduce = "maximum"',
            "plots[0].reduce",
            "must be 'max', 'min', 'mean', 'median' or 'count' (got 'maximum')",
        ),
        (
            'x = "integration.dt"\ny = "method"\nreduce = "max"',
            "plots[0].y",
            "'method' is a text; give it as `series`",
        ),
        (
            'x = "integration.method"\ny = "steps"\nreduce = "max"\nlog_x = true',
            "plots[0].x",
            "`log_x` needs numbers",
        ),
        (
            'x = "integration.dt"\ny = "steps"\nseries = "integration.method"',
            "plots[0].reduce",
            "differing in entities[pair].stiffness (2 values); give `reduce`",
        ),
        (
            'x = "integration.dt"\ny = "steps"\nreduce = "max"\nonly = "succeeded"',
            "plots[0].only",
            "must be 'all', 'success' or 'failed'",
        ),
        (
            'x = "integration.dt"\ny = "steps"\nreduce = "max"\nserie = "integration.method"',
            "plots[0].serie",
            "unknown key. Did you mean 'series'? Allowed: x, y, series, reduce, only",
        ),
        (
            'x = "integration.dt"\ny = "steps"\nreduce = "max"\nname = "../escape"',
            "plots[0].name",
            "should match pattern",
        ),
    ],
)
def test_bad_plots_are_refused_at_load_with_their_line(plot, where, message):
    text = plotted(f"[[plots]]\n{plot}\n")
    refused = refusal(text)
    assert f"{where}: " in refused and message in refused, refused
    key = where.rsplit(".", 1)[1]
    # The key's own line, or the [[plots]] header's for a key the table lacks.
    needle = f"{key} = " if f"\n{key} = " in text else "[[plots]]"
    assert f"s.toml:{line_of(text, needle)}: {where}" in refused


def test_every_plot_problem_is_reported_at_once_and_names_are_checked():
    text = plotted(
        """
[[plots]]
x = "integration.dtt"
y = "steps"
reduce = "max"
[[plots]]
x = "integration.dt"
y = "integration.method"
reduce = "max"
name = "same"
[[plots]]
x = "entities[pair].stiffness"
y = "integration.dt"
series = "entities[pair].stiffness"
reduce = "max"
name = "same"
"""
    )
    refused = refusal(text)
    assert refused.startswith("5 problems in the sweep:")
    assert "plots[0].x: `x` must be one of the sweep's parameter paths" in refused
    assert "plots[1].y: `y` is drawn as a number, and this parameter takes other values" in refused
    assert "plots[2].series: `series` and `x` are the same parameter" in refused
    assert refused.count("the name 'same' is given to several plots") == 2


def test_plots_are_named_uniquely_and_nested_figures_accepted_at_load():
    sweep = parse_sweep(
        plotted(
            """
[[plots]]
x = "integration.dt"
y = "max_energy_error"
reduce = "max"
[[plots]]
x = "integration.dt"
y = "max_energy_error"
reduce = "max"
only = "all"
[[plots]]
x = "integration. dt"
y = "counts.particles"
reduce = "mean"
[[plots]]
x = "entities[pair].stiffness"
y = "integration.dt"
series = "integration.method"
reduce = "max"
name = "max_stable_dt"
log_x = true
"""
        )
    )
    assert [p.name for p in sweep.plots] == [
        "max_max_energy_error_vs_dt",
        "max_max_energy_error_vs_dt-2",
        "mean_particles_vs_dt",
        "max_stable_dt",
    ]
    assert sweep.plots[3].only == "success" and sweep.plots[3].log_x and not sweep.plots[3].log_y
    assert sweep.plots[2].x == "integration.dt"  # as the table's column is named


_columns = st.sampled_from(
    ["integration.dt", "integration.method", "entities[pair].stiffness", "steps", "energy_drift",
     "counts.particles", "method", "world.gravity", "integration.dt ", "", "x" * 600]
)  # fmt: skip
_anything = st.one_of(
    st.none(), st.booleans(), st.integers(-(2**70), 2**70), st.floats(), st.text(max_size=8),
    st.lists(st.integers(), max_size=2),
)  # fmt: skip
_plot = st.fixed_dictionaries(
    {"x": _columns | _anything, "y": _columns | _anything},
    optional={
        "series": _columns | _anything,
        "reduce": st.sampled_from(["max", "min", "mean", "median", "count", "sum"]) | _anything,
        "only": st.sampled_from(["all", "success", "failed"]) | _anything,
        "log_x": _anything, "log_y": _anything, "abs_y": _anything, "title": _anything,
        "name": st.sampled_from(["a", "a", "b.c", "../x", "-x"]) | _anything,
        "extra": _anything,
    },
)  # fmt: skip


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(plots=st.lists(_plot, max_size=3) | _anything)
def test_hostile_plots_are_refused_or_reduced_without_a_traceback(plots):
    document = tomllib.loads(plotted("")) | {"plots": plots}
    try:
        sweep = parse_sweep(json.dumps(document), "json")
    except ModelError as error:
        assert str(error).strip()
        return
    rows = [
        {"index": i, "run": str(i), "success": i % 2 == 0, "integration.dt": 0.01 * (i + 1),
         "integration.method": "rk4" if i < 2 else "euler", "entities[pair].stiffness": 10.0,
         "steps": i, "energy_drift": [None, float("nan"), -1.0, "inf"][i]}
        for i in range(4)
    ]  # fmt: skip
    names = [plot.name for plot in sweep.plots]
    assert len(set(names)) == len(names)
    for plot in sweep.plots:
        found = reduce_plot(plot, rows)
        assert sum(p.runs for p in found.points) + sum(found.left_out.values()) == 4


# ---------------------------------------------------------------- reductions


#: (method, k, figure) of each run by hand: run 5 failed, runs 7 and 8 have no finite figure.
BY_HAND = [
    ("a", 1.0, 3.0), ("a", 1.0, -1.0), ("a", 1.0, 2.0),
    ("a", 4.0, 5.0), ("a", 4.0, 7.0), ("a", 4.0, 100.0),
    ("b", 1.0, 10.0), ("b", 1.0, None), ("b", 1.0, float("nan")),
    ("b", 4.0, -20.0), ("b", 4.0, 40.0), ("b", 4.0, 30.0),
]  # fmt: skip
#: The (series, x) groups in drawing order, and the runs each point stands for.
GROUPS = [("a", 1.0), ("a", 4.0), ("b", 1.0), ("b", 4.0)]
RUNS = [3, 2, 1, 3]


def rows_by_hand() -> list[dict]:
    return [
        {"index": i, "run": f"{i:02d}", "k": k, "method": method, "success": i != 5,
         "error": "diverged" if i == 5 else None, "figure": y}
        for i, (method, k, y) in enumerate(BY_HAND)
    ]  # fmt: skip


def points(**keys) -> list[tuple]:
    plot = Plot(x="k", y="figure", series="method", **keys)
    found = reduce_plot(plot, rows_by_hand())
    return [(p.series, p.x, p.y, p.runs) for p in found.points]


@pytest.mark.parametrize(
    ("reduce", "ys"),
    [
        ("max", [3.0, 7.0, 10.0, 40.0]),
        ("min", [-1.0, 5.0, 10.0, -20.0]),
        ("mean", [4 / 3, 6.0, 10.0, 50 / 3]),
        ("median", [2.0, 6.0, 10.0, 30.0]),
        ("count", [3.0, 2.0, 1.0, 3.0]),
    ],
)
def test_reductions_group_by_x_and_series_over_the_successful_runs(reduce, ys):
    # Run 5 (failed) is left out by only = "success", runs 7 and 8 have no finite figure.
    expected = [
        (series, x, pytest.approx(y), runs)
        for (series, x), y, runs in zip(GROUPS, ys, RUNS, strict=True)
    ]
    assert points(reduce=reduce) == expected


def test_only_abs_y_and_what_is_left_out():
    assert points(reduce="max", only="failed") == [("a", 4.0, 100.0, 1)]
    assert points(reduce="max", only="all")[1] == ("a", 4.0, 100.0, 3)
    assert points(reduce="max", abs_y=True)[3] == ("b", 4.0, 40.0, 3)
    assert points(reduce="min", abs_y=True)[0] == ("a", 1.0, 1.0, 3)
    found = reduce_plot(Plot(x="k", y="figure", series="method", reduce="max"), rows_by_hand())
    assert found.left_out == {"not successful (only = success)": 1, "no finite figure": 2}
    assert found.y_label == "max(figure)"
    assert [value for value, _ in found.lines()] == ["a", "b"]


def test_without_reduce_each_run_is_a_point_and_text_x_keeps_its_order():
    rows = [
        {"index": i, "success": True, "m": m, "y": float(i)}
        for i, m in enumerate(["rk4", "euler", "rk4", "verlet"])
    ]
    found = reduce_plot(Plot(x="m", y="y"), rows)
    assert found.categorical and found.x_order == ("rk4", "euler", "verlet")
    assert [(p.x, p.y, p.runs) for p in found.points] == [
        ("rk4", 0.0, 1), ("rk4", 2.0, 1), ("euler", 1.0, 1), ("verlet", 3.0, 1)
    ]  # fmt: skip
    numbers = reduce_plot(Plot(x="y", y="index", reduce="max"), list(reversed(rows)))
    assert not numbers.categorical and [p.x for p in numbers.points] == [0.0, 1.0, 2.0, 3.0]


# ---------------------------------------------------------------- results.h5


def test_results_h5_reads_back_to_the_same_values(tmp_path):
    rows = [
        {"index": 0, "run": "0-a", "a/b": 1.5, "vec": [0.0, -9.81, 0.0], "success": True,
         "error": None, "steps": 10, "drift": 0.25, "complete": True, "note": "ünïcode"},
        {"index": 1, "run": "1-b", "a/b": 2.0, "vec": [1.0, 2.0, 3.0], "success": False,
         "error": "diverged <at> t=1", "steps": None, "drift": float("nan"), "complete": None},
        {"index": 2, "run": "2-c", "a/b": 3, "vec": [0.0, 0.0, 0.0], "success": True,
         "error": None, "steps": 12, "drift": float("inf"), "complete": False, "note": "x"},
    ]  # fmt: skip
    columns = [
        "index",
        "run",
        "a/b",
        "vec",
        "success",
        "error",
        "steps",
        "drift",
        "complete",
        "note",
    ]
    heading = {"sweep": "s<1>", "design": "grid", "seed": 7, "runs_total": 4, "description": "d"}
    path = write_results_h5(tmp_path / "results.h5", heading, ["a/b", "vec"], columns, rows)
    attributes, back = read_results_h5(path)
    assert attributes == heading | {"parameters": ["a/b", "vec"], "columns": columns}
    assert len(back) == 3
    for row, read in zip(rows, back, strict=True):
        assert list(read) == columns
        for column in columns:
            value, got = row.get(column), read[column]
            if isinstance(value, float) and math.isnan(value):
                assert isinstance(got, float) and math.isnan(got), column
            else:
                assert (got == value and type(got) is type(value)) or column == "a/b", column
    assert [r["a/b"] for r in back] == [1.5, 2.0, 3.0]  # an int among floats is a float
    with h5py.File(path) as file:
        data = file["columns"]
        assert data["a%2Fb"].dtype == np.float64 and data["steps"].dtype == np.int64
        assert data["success"].dtype == np.bool_ and data["run"].attrs["kind"] == "text"
        assert data["vec"].attrs["kind"] == "json" and data["drift"].attrs["kind"] == "float"
        assert list(file["missing"]) == ["complete", "error", "note", "steps"]
        assert file["missing"]["steps"][()].tolist() == [False, True, False]


def test_results_h5_of_no_runs(tmp_path):
    path = write_results_h5(tmp_path / "r.h5", {"sweep": "s"}, ["p"], ["index", "p"], [])
    attributes, rows = read_results_h5(path)
    assert rows == [] and attributes["columns"] == ["index", "p"]


# ---------------------------------------------------------------- plots and the page


def test_a_plot_with_nothing_to_draw_still_writes_its_table_and_figure(tmp_path):
    rows = [{"index": i, "success": False, "k": float(i), "y": 1.0} for i in range(3)]
    files = write_plot(tmp_path / "plots", Plot(x="k", y="y", name="empty", log_y=True), rows)
    assert [f.name for f in files] == ["empty.csv", "empty.png", "empty.svg"]
    assert (tmp_path / "plots" / "empty.csv").read_text().splitlines() == ["k,y,runs"]
    with Image.open(tmp_path / "plots" / "empty.png") as image:
        assert image.size == PLOT_SIZE
    assert not [p for p in (tmp_path / "plots").iterdir() if p.name.startswith(".")]


class Links(html.parser.HTMLParser):
    """Every href and src of a page, and its visible text."""

    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []
        self.text: list[str] = []
        self.scripts = 0

    def handle_starttag(self, tag, attrs):
        self.scripts += tag == "script"
        self.links += [value for name, value in attrs if name in ("href", "src") and value]

    def handle_data(self, data):
        self.text.append(data)


def parsed(page: Path) -> Links:
    parser = Links()
    parser.feed(page.read_text(encoding="utf-8"))
    return parser


def test_user_text_on_the_page_is_escaped(tmp_path):
    hostile = "<script>alert(1)</script>"
    rows = [
        {"index": 0, "run": "0-x", "p": hostile, "success": False, "error": f"failed: {hostile}"},
        {"index": 1, "run": "1-y", "p": "a & b", "success": True, "error": None, "steps": 3},
    ]
    (tmp_path / "runs" / "0-x").mkdir(parents=True)
    (tmp_path / "runs" / "0-x" / "summary.json").write_text("{}")
    heading = {"sweep": hostile, "description": f'"{hostile}"', "runs_total": 2}
    page = write_index(tmp_path, heading, ["p"], rows, [], [f"plot {hostile!r} failed"])
    parser = parsed(page)
    assert parser.scripts == 1  # the page's own sorting script, nothing from the user
    text = "".join(parser.text)
    # The name (title and heading), the description, a value, an error and a warning.
    assert text.count(hostile) == 6
    assert "a & b" in text and "1 succeeded, 1 failed" in text
    assert parser.links == ["runs/0-x/", "runs/0-x/summary.json"]


@pytest.fixture(scope="module")
def stability(tmp_path_factory):
    """The spring_stability example, shortened: k = 100 and 400 N/m, the example's seven
    largest steps (0.0882 to 0.3528 s), 10 s per run."""
    root = tmp_path_factory.mktemp("stability")
    data = tomllib.loads((EXAMPLES / "spring_stability.toml").read_text())
    data["scene"]["integration"]["duration"] = 10.0
    stiffness, _, dt = data["parameters"]
    stiffness["log_range"] = [100.0, 400.0, 2]
    assert dt["log_range"] == [0.0441, 0.3528, 10]
    dt["log_range"] = [0.0882, 0.3528, 7]
    path = root / "short.json"
    path.write_text(json.dumps(data))
    return vv.sweep(path, root / "out", executor="serial")


def test_largest_stable_step_follows_the_theory_of_the_undamped_oscillator(stability):
    """m x'' = −k x: ω = √(k/m), and the step's amplification R(iωh) decides stability. Symplectic
    Euler is stable for ωh < 2 and RK4 for ωh < 2√2 (its stability region meets the imaginary
    axis at ±2√2; the 2.785 of the real axis is for decaying modes). Every step below the limit
    runs the 10 s, every step above it diverges, so the largest stable step on the grid is the
    largest grid value below the limit."""
    assert stability.ran == 42 and not stability.warnings
    runs = {
        (
            r["entities[spring].parameters.stiffness"],
            r["integration.method"],
            r["integration.dt"],
        ): r
        for r in stability.rows
    }
    grid = sorted({dt for _, _, dt in runs})
    ratio = grid[1] / grid[0]
    assert ratio == pytest.approx(2 ** (1 / 3))
    largest: dict[tuple[str, float], float] = {}
    for k in (100.0, 400.0):
        omega = math.sqrt(k / 1.0)
        for method, limit in (("symplectic_euler", 2.0), ("rk4", 2.0 * math.sqrt(2.0))):
            for dt in grid:
                row = _row(runs, k, method, dt)
                assert row["success"] is (omega * dt < limit), (k, method, dt, row["error"])
            largest[(method, k)] = max(dt for dt in grid if omega * dt < limit)
            # The grid resolves the limit: the next step up is above it.
            assert largest[(method, k)] < limit / omega <= largest[(method, k)] * ratio
    # The plot's table holds the same maxima, one line per method.
    with (stability.directory / "plots" / "max_stable_dt.csv").open() as handle:
        table = list(csv.DictReader(handle))
    assert {
        (r["integration.method"], round(float(r["entities[spring].parameters.stiffness"])))
        : float(r["max(integration.dt)"]) for r in table
    } == {(m, round(k)): dt for (m, k), dt in largest.items()}  # fmt: skip
    # h_max ∝ 1/ω = √(m/k): slope −1/2 in log–log. Exactly, here: a 4× stiffer spring halves the
    # limit, and 2 = ratio³, so its largest stable step is three grid values lower.
    for method in ("symplectic_euler", "rk4"):
        slope = math.log(largest[(method, 400.0)] / largest[(method, 100.0)]) / math.log(4.0)
        assert slope == pytest.approx(-0.5, abs=1e-12)


def _row(runs: dict, k: float, method: str, dt: float) -> dict:
    return next(
        r for (kk, m, d), r in runs.items() if math.isclose(kk, k) and m == method and d == dt
    )


def test_explicit_euler_grows_the_energy_at_every_step_and_always_diverges(stability):
    """Explicit Euler on x'' = −ω²x maps z = (ωx, v) to a rotation of z scaled by
    ρ = |R(iωh)| = √(1 + (ωh)²) > 1: the energy grows by ρ² per step whatever h. From
    |z₀| = ω·0.1 m, the largest component passes the watch's limit 1e10 between the step where
    |z| does (ln(1e10/|z₀|)/ln ρ) and a half turn (π/atan(ωh) steps) later."""
    euler = [r for r in stability.rows if r["integration.method"] == "explicit_euler"]
    assert len(euler) == 14
    for row in euler:
        assert not row["success"] and "diverged" in row["error"]
        assert "'explicit_euler' is unstable for every step" in row["error"]
        omega, h = math.sqrt(row["entities[spring].parameters.stiffness"]), row["integration.dt"]
        rho = math.sqrt(1.0 + (omega * h) ** 2)
        first = math.log(1e10 / (0.1 * omega)) / math.log(rho)
        assert first <= row["steps"] <= first + math.pi / math.atan(omega * h) + 2, row


def test_the_sweep_writes_the_plot_the_h5_table_and_an_index_whose_links_resolve(stability):
    root = stability.directory
    names = {path.relative_to(root).as_posix() for path in stability.files}
    assert names == {
        "results.csv", "results.json", "results.h5", "index.html",
        "plots/max_stable_dt.csv", "plots/max_stable_dt.png", "plots/max_stable_dt.svg",
    }  # fmt: skip
    with Image.open(root / "plots" / "max_stable_dt.png") as image:
        assert image.format == "PNG" and image.size == PLOT_SIZE
        pixels = np.asarray(image.convert("RGB")).reshape(-1, 3)
    assert len(np.unique(pixels, axis=0)) > 50  # lines, markers, text: not a blank canvas
    _, rows = read_results_h5(root / "results.h5")
    assert [r["run"] for r in rows] == [r["run"] for r in stability.rows]
    assert [r["success"] for r in rows] == [r["success"] for r in stability.rows]
    parser = parsed(root / "index.html")
    relative = [link for link in parser.links if not urlparse(link).scheme]
    assert relative == parser.links  # nothing outside the sweep's directory
    for link in relative:
        assert (root / unquote(link)).exists(), link
    assert "plots/max_stable_dt.png" in relative
    assert sum(link.endswith("/summary.json") for link in relative) == 42
    text = "".join(parser.text)
    # Stable: symplectic Euler 4 and 1 steps, RK4 6 and 3 (k = 100, 400 N/m); explicit Euler none.
    assert "42 of 42 runs: 14 succeeded, 28 failed" in text


def test_the_index_loads_from_file_with_its_plot_and_sorts(stability):
    if not CHROMIUM.is_file():
        pytest.fail(f"the page test needs Debian's Chromium at {CHROMIUM}", pytrace=False)
    page_path = stability.directory / "index.html"
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_FLAGS)
        try:
            page = browser.new_page()
            requests, failed, errors = [], [], []
            page.on("request", lambda request: requests.append(request.url))
            page.on("requestfailed", lambda request: failed.append(request.url))
            page.on("pageerror", lambda error: errors.append(str(error)))
            page.goto(page_path.as_uri())
            page.wait_for_load_state("load")
            widths = page.eval_on_selector_all("img", "images => images.map(i => i.naturalWidth)")
            assert widths == [PLOT_SIZE[0]]
            assert failed == [] and errors == []
            assert all(url.startswith(stability.directory.as_uri()) for url in requests)
            page.click("#runs th:nth-child(1)")  # index: ascending, then descending
            page.click("#runs th:nth-child(1)")
            first = page.inner_text("#runs tbody tr:first-child td:first-child")
            assert first == "41"
        finally:
            browser.close()


# ---------------------------------------------------------------- failures and interrupts


def test_a_plot_that_fails_to_draw_costs_only_itself(stability, tmp_path, monkeypatch):
    from visviva.sweeps import load_sweep

    def broken(*args, **kwargs):
        raise RuntimeError("no fonts")

    monkeypatch.setattr("visviva.viz.sweep_plots.plot_against_parameter", broken)
    sweep = load_sweep(EXAMPLES / "spring_stability.toml")
    heading = {"sweep": "s", "design": "grid", "seed": 0, "runs_total": 42}
    reports = write_reports(tmp_path, sweep, heading, stability.rows)
    assert reports.warnings == ("plot 'max_stable_dt' was not drawn: RuntimeError: no fonts",)
    # The plot's table is written before its figure is drawn, and kept.
    assert {p.name for p in reports.files} == {"results.h5", "max_stable_dt.csv", "index.html"}
    page = parsed(tmp_path / "index.html")
    assert "warning: plot 'max_stable_dt' was not drawn" in "".join(page.text)
    assert not any(link.startswith("plots/") for link in page.links)


def test_an_interrupted_sweep_still_writes_its_reports(tmp_path):
    text = spring_sweep(
        GRID + '[[plots]]\nx = "entities[pair].stiffness"\ny = "steps"\nseries = '
        '"integration.method"\n'
    ).replace("duration = 0.5", "duration = 0.05")
    out = tmp_path / "out"
    with pytest.raises(SweepInterrupted) as caught:
        vv.sweep(write(tmp_path, text), out, executor=InlineExecutor(interrupt_at=3), batch=False)
    assert len(caught.value.result.rows) == 3
    table = list(csv.reader((out / "plots" / "steps_vs_stiffness.csv").open()))
    assert table[0] == ["entities[pair].stiffness", "integration.method", "steps", "runs"]
    assert table[1:] == [  # the three finished runs, by series then x; 0.05 s in steps of 0.01 s
        ["10.0", "explicit_euler", "5.0", "1"],
        ["100.0", "explicit_euler", "5.0", "1"],
        ["10.0", "rk4", "5.0", "1"],
    ]
    assert "3 of 6 runs (3 not finished)" in (out / "index.html").read_text()
    assert len(read_results_h5(out / "results.h5")[1]) == 3


def test_the_command_prints_the_files_and_the_warnings(stability, capsys):
    from dataclasses import replace

    from visviva.cli.sweeps import _print_result

    _print_result(replace(stability, warnings=("plot 'p' was not drawn: RuntimeError: x",)))
    out, err = capsys.readouterr()
    assert out.splitlines()[-1] == (
        "wrote results.csv, results.json, results.h5, index.html and 1 plot in plots/ into "
        f"{stability.directory}/"
    )
    assert err == "warning: plot 'p' was not drawn: RuntimeError: x\n"


def test_importing_visviva_and_its_sweeps_loads_no_matplotlib():
    code = "import sys, visviva, visviva.sweeps.reports; print('matplotlib' in sys.modules)"
    found = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert found.stdout.strip() == "False"
