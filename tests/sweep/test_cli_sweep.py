"""fleet-async sweep: the console script end to end, and its progress line."""

from __future__ import annotations

import io
import os
import shutil
import subprocess
from pathlib import Path

import pytest
from PIL import Image

from fleet_async.cli import main
from fleet_async.cli.progress import RunsProgressBar, format_runs_progress
from fleet_async.sweep import read_table
from tests.sweep.sweep_scenarios import ref

SCENARIO = """\
simulation: {timestep: 0.1, duration: 2.0}
entities:
  - name: r0
    urdf_path: simple_cube
    pose: [0.0, 0.0, 0.1]
    controller: {type: omni, max_linear_vel: 1.0}
    actions: [{type: move, path: [[1.0, 0.0, 0.1]]}]
"""


@pytest.fixture(scope="module")
def script() -> str:
    path = shutil.which("fleet-async")
    assert path is not None, 'fleet-async is not installed: pip install -e ".[test]"'
    return path


@pytest.fixture
def scenario(tmp_path: Path) -> Path:
    path = tmp_path / "one.yaml"
    path.write_text(SCENARIO)
    return path


def cli(script: str, *args: str | Path, hide: str | None = None, tmp: Path | None = None):
    """Run the console script; ``hide`` makes that module fail to import."""
    env = dict(os.environ)
    if hide is not None:
        assert tmp is not None
        shadow = tmp / "shadow" / hide
        shadow.mkdir(parents=True)
        (shadow / "__init__.py").write_text(f"raise ImportError('{hide} hidden by the test')\n")
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (str(shadow.parent), env.get("PYTHONPATH")) if p
        )
    return subprocess.run(
        [script, *map(str, args)], capture_output=True, text=True, timeout=300, env=env, check=False
    )


def error_line(stderr: str) -> str:
    lines = [line for line in stderr.splitlines() if line.startswith("fleet-async: error: ")]
    assert len(lines) == 1, stderr
    return lines[0]


def test_sweep_writes_the_table_and_the_plot(script, scenario, tmp_path):
    out, png = tmp_path / "results.csv", tmp_path / "kpi.png"
    args = [
        "sweep",
        scenario,
        "--seeds",
        "0:2",
        "--set",
        "entities.r0.controller.max_linear_vel=0.5,1",
    ]
    result = cli(script, *args, "--out", out, "--plot", png, "--y", "moving_time_mean_s")
    assert result.returncode == 0, result.stderr
    assert "4 runs: 4 ran on pool of 2 workers, 0 were already in" in result.stdout
    assert "0 failed" in result.stdout and f"plot: {png}" in result.stdout
    rows = read_table(out)
    assert [(r["entities.r0.controller.max_linear_vel"], r["seed"]) for r in rows] == [
        ("0.5", "0"),
        ("1", "0"),
        ("0.5", "1"),
        ("1", "1"),
    ]
    with Image.open(png) as image:
        assert image.format == "PNG" and image.size[0] > 400
    again = cli(script, *args, "--out", out, "--engine", "inline")
    assert again.returncode == 0 and "0 ran on inline, 4 were already in" in again.stdout


def test_a_sweep_branches_from_a_run_saved_with_save_state(script, scenario, tmp_path):
    warm = tmp_path / "warm.ckpt"
    saved = cli(script, "run", scenario, "--duration", "0.5", "--save-state", warm, "--quiet")
    assert saved.returncode == 0, saved.stderr
    out = tmp_path / "branches.csv"
    result = cli(
        script,
        "sweep",
        scenario,
        "--checkpoint",
        warm,
        "--duration",
        "1",
        "--seeds",
        "0:2",
        "--engine",
        "inline",
        "--out",
        out,
    )
    assert result.returncode == 0, result.stderr
    rows = read_table(out)
    assert [r["steps"] for r in rows] == ["10", "10"]
    # 0.5 s of the 1 m move happened before the checkpoint: this branch drives the rest.
    assert float(rows[0]["distance_total_m"]) < 1.0


def test_an_unknown_key_names_it_and_the_valid_ones(script, scenario, tmp_path):
    result = cli(script, "sweep", scenario, "--set", "entities.r0.controler.type=omni")
    assert result.returncode == 2
    line = error_line(result.stderr)
    assert "--set entities.r0.controler.type:" in line
    assert "did you mean 'entities.r0.controller.type'?" in line
    assert "valid keys: entities.r0.actions, entities.r0.controller.max_linear_vel" in line
    assert not (tmp_path / "results.csv").exists()


def test_keys_lists_what_set_accepts(script, scenario):
    result = cli(script, "sweep", scenario, "--keys")
    assert result.returncode == 0
    keys = result.stdout.split()
    assert "entities.r0.controller.max_linear_vel" in keys and "simulation.timestep" in keys


def test_failed_runs_are_rows_and_exit_1(script, tmp_path):
    out = tmp_path / "results.csv"
    result = cli(
        script,
        "sweep",
        ref("random_fleet"),
        "--set",
        "robots=1,2",
        "--set",
        "fail_at=2",
        "--duration",
        "1",
        "--engine",
        "inline",
        "--out",
        out,
    )
    assert result.returncode == 1, result.stderr
    assert "1 failed" in result.stdout
    assert "run 1 (seed 0): ValueError: no fleet of 2 today" in result.stdout
    assert [r["error"] for r in read_table(out)] == ["", "ValueError: no fleet of 2 today"]


@pytest.mark.parametrize(
    ("module", "args", "extra"),
    [
        ("matplotlib", ["--plot", "kpi.png"], "fleet-async[plot]"),
        ("ray", ["--engine", "ray"], "fleet-async[ray]"),
    ],
)
def test_a_missing_extra_is_named_before_anything_runs(
    script, scenario, tmp_path, module, args, extra
):
    out = tmp_path / "results.csv"
    result = cli(
        script,
        "sweep",
        scenario,
        "--set",
        "simulation.timestep=0.1",
        "--out",
        out,
        *args,
        hide=module,
        tmp=tmp_path,
    )
    assert result.returncode == 2
    assert f"pip install '{extra}'" in error_line(result.stderr)
    assert not out.exists()


def test_bad_options_are_usage_errors(capsys):
    for argv in (["sweep", "x.yaml", "--seeds", "3:1"], ["sweep", "x.yaml", "--set", "novalue"]):
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "the range is empty" in err and "expected KEY=VALUE" in err


def test_plot_needs_a_swept_key_and_a_kpi(scenario, capsys):
    assert main(["sweep", str(scenario), "--plot", "p.png"]) == 2
    assert (
        main(
            [
                "sweep",
                str(scenario),
                "--set",
                "simulation.timestep=0.1",
                "--plot",
                "p.png",
                "--y",
                "nope",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "--plot needs a swept parameter" in err and "--y nope: not a KPI" in err


class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_runs_progress_line():
    assert (
        format_runs_progress(25, 100, 2, 30.4, width=8)
        == "[##......]  25/100 runs  2 failed  ETA 30 s"
    )
    assert format_runs_progress(0, 10, 0, None, width=4) == "[....]  0/10 runs  0 failed  ETA -"


def test_runs_progress_bar_estimates_from_the_runs_it_ran():
    now = [0.0]
    stream = FakeTerminal()
    bar = RunsProgressBar(100, stream, skipped=20, min_interval=0.1, clock=lambda: now[0])
    bar.start()
    now[0] = 10.0
    bar.failed = 1
    assert bar.update(30)  # 10 runs in 10 s: 70 left take 70 s
    assert stream.getvalue().endswith("30/100 runs  1 failed  ETA 70 s")


class _Payload:
    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (eval, (f"open({str(self.marker)!r}, 'w').write('pwned')",))


def test_a_planted_pickle_checkpoint_runs_nothing_without_unsafe(scenario, tmp_path, capsys):
    import pickle

    marker, planted = tmp_path / "marker", tmp_path / "gift.ckpt"
    planted.write_bytes(pickle.dumps(_Payload(marker)))
    out = tmp_path / "b.csv"
    args = ["sweep", str(scenario), "--checkpoint", str(planted), "--seeds", "0:2"]
    code = main([*args, "--engine", "inline", "--out", str(out), "--quiet"])
    assert code != 0 and not marker.exists()
    rows = read_table(out)
    assert all("gift.ckpt is a format-1 checkpoint, a pickle" in r["error"] for r in rows)
    assert all("--unsafe" in r["error"] for r in rows)
    out.unlink()
    main([*args, "--engine", "inline", "--out", str(out), "--quiet", "--unsafe"])
    assert marker.exists()  # what --unsafe means: the file's code runs
