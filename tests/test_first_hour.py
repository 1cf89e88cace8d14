"""The first hour of a new user: each friction they met, tried as they tried it, in a subprocess."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from train.env_ids import DEFAULT_ENV_ID, HELD_ENV_ID, PAPER_ENV_ID, TASK_ENV_ID

ROOT = Path(__file__).resolve().parents[1]


def dwr_gym(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, "-m", "train.cli", *args], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=600)  # fmt: skip


# 1. One env id story: v2, the task held to T_con, is every command's default and the newest id, so it does not warn;
# v1 is the task ending on arrival (its agents keep it); v0 is the paper's reward, kept for reproduction.


def test_train_takes_the_env_id_and_records_it_with_the_discount_of_that_env(tmp_path: Path) -> None:
    result = dwr_gym("train", "--env", TASK_ENV_ID, "--total-timesteps", "512", "--num-envs", "4", "--hyperparams",
                     "n_steps=128", "--eval-freq", "512", "--eval-episodes", "4", "--run-dir", "v1", "--no-progress",
                     cwd=tmp_path)  # fmt: skip
    assert result.returncode == 0, result.stderr
    config = yaml.safe_load((tmp_path / "v1" / "config.yaml").read_text())["config"]
    assert config["env_id"] == TASK_ENV_ID and config["algo_kwargs"]["gamma"] == 0.999


def test_the_default_env_is_the_task_held_to_T_con_and_v0_keeps_its_own_hyperparameters() -> None:
    from train.learning.config import TrainConfig
    from train.learning.hyperparams import resolve_hyperparams

    task = resolve_hyperparams(TrainConfig(), set())
    assert DEFAULT_ENV_ID == HELD_ENV_ID and task.env_id == HELD_ENV_ID
    assert task.env_params().T_con_range == (10.0, 60.0) and task.env_params().hold_to_T_con
    assert task.algo_kwargs["gamma"] == 1.0  # the discount v2's return is defined with
    paper = resolve_hyperparams(TrainConfig(env_id=PAPER_ENV_ID), set())
    assert paper.env_params().T_con_range is None and paper.algo_kwargs["gamma"] == 0.99


def test_a_run_that_recorded_no_env_id_loads_as_v0_and_the_shipped_agents_record_theirs(tmp_path: Path) -> None:
    from train.learning.agents import PRETRAINED, trained_env_id
    from train.learning.runs import load_config

    (tmp_path / "config.yaml").write_text(yaml.safe_dump({"config": {"algo": "ppo", "env_kwargs": {}}}))
    old = load_config(tmp_path)
    assert old.env_id == PAPER_ENV_ID and old.env_params().T_con_range is None
    shipped = {name: trained_env_id(path) for name, path in PRETRAINED.items()}
    assert shipped == {"apg-v2": HELD_ENV_ID, "apg-residual-ptc-v2": HELD_ENV_ID, "ppo-jax-v1": TASK_ENV_ID,
                       "es-v1": TASK_ENV_ID, "robust": TASK_ENV_ID, "ppo": PAPER_ENV_ID,
                       "residual-ppo": PAPER_ENV_ID}  # fmt: skip


def test_evaluate_runs_on_the_task_the_paper_sets_keep_their_T_con_and_T_con_replaces_the_range(
    tmp_path: Path,
) -> None:
    common = ["--controllers", "ptc", "--scenarios", "paper-fig5", "random", "--n", "5", "--optimum", "none",
              "--no-progress"]  # fmt: skip
    task = dwr_gym("evaluate", *common, "--out", str(tmp_path / "task"), "--agent", str(ROOT / "train/pretrained/ppo"))
    assert task.returncode == 0, task.stderr
    rows = json.loads((tmp_path / "task" / "evaluation.json").read_text())
    assert {(r["scenario"], r["T_con"], r["env_id"]) for r in rows} == {("paper-fig5", 20.0, DEFAULT_ENV_ID),
                                                                         ("random", None, DEFAULT_ENV_ID)}  # fmt: skip
    assert "random, T_con drawn per episode" in task.stdout
    assert f"note: ppo trained on {PAPER_ENV_ID}, run here on {DEFAULT_ENV_ID}" in task.stderr
    fixed = dwr_gym("evaluate", *common, "--T-con", "30", "--out", str(tmp_path / "fixed"))
    assert fixed.returncode == 0, fixed.stderr
    assert [r["T_con"] for r in json.loads((tmp_path / "fixed" / "evaluation.json").read_text())] == [30.0, 30.0]
    paper = dwr_gym("evaluate", *common, "--env", PAPER_ENV_ID, "--out", str(tmp_path / "paper"))
    assert paper.returncode == 0, paper.stderr
    assert [r["T_con"] for r in json.loads((tmp_path / "paper" / "evaluation.json").read_text())] == [20.0, 20.0]


# 2. `--env` is an option of its own, and no option is guessed from a prefix.


@pytest.mark.parametrize("command", ["train", "evaluate", "compare", "robustness", "sweep", "imitate"])
def test_every_command_that_makes_an_env_takes_env_and_refuses_an_abbreviation(command: str) -> None:
    wrong = dwr_gym(command, "--env", "CartPole-v1")
    assert wrong.returncode == 2 and "--env 'CartPole-v1' is invalid: expected DWRPointStabilization-v2" in wrong.stderr
    abbreviated = dwr_gym(command, "--env-kw", "T_con=25")
    assert abbreviated.returncode == 2 and "unrecognized arguments: --env-kw" in abbreviated.stderr


# 3. One spelling for one concept: --agents in every command, --agent (repeatable) meaning the same.


def test_evaluate_takes_agent_as_agents(tmp_path: Path) -> None:
    ppo, ppo_jax = str(ROOT / "train/pretrained/ppo"), str(ROOT / "train/pretrained/ppo_jax_v1")
    result = dwr_gym("evaluate", "--controllers", "ptc", "--scenarios", "paper-fig5", "--optimum", "none",
                     "--no-progress", "--out", str(tmp_path), "--agent", ppo, "--agent", ppo_jax)  # fmt: skip
    assert result.returncode == 0, result.stderr
    rows = json.loads((tmp_path / "evaluation.json").read_text())
    assert [row["policy"] for row in rows] == ["ptc", "ppo", "ppo-jax-v1"]


@pytest.mark.parametrize("command", ["evaluate", "compare", "robustness"])
def test_every_command_with_agents_reads_both_spellings(command: str) -> None:
    from train.cli import build_parser

    parser = build_parser()
    assert parser.parse_args([command, "--agents", "a", "b"]).agents == ["a", "b"]
    assert parser.parse_args([command, "--agent", "a", "--agent", "b"]).agents == ["a", "b"]


# 4. The help says what the options take, each default once, and lists every command.


def option_entries(help_text: str) -> dict[str, str]:
    """Each option's entry in ``--help`` (flags and help text, wrapped lines joined), by its first flag."""
    entries: dict[str, str] = {}
    flag = None
    for line in help_text.split("options:", 1)[1].splitlines():
        if line.startswith("  -"):
            flag = line.split()[0].rstrip(",")
            entries[flag] = line.strip()
        elif flag is not None and line.startswith("      "):
            entries[flag] += " " + line.strip()
    return entries


def test_help_lists_every_command_and_each_option_says_its_default_once() -> None:
    from train.cli import build_parser

    top = dwr_gym("--help").stdout
    description = " ".join(top.split("positional arguments:")[0].split())
    commands = list(build_parser()._subparsers._group_actions[0].choices)  # type: ignore[union-attr]
    modules = {path.stem for path in Path(build_parser.__code__.co_filename).parent.glob("commands/*.py")}
    assert set(commands) == modules - {"__init__", "shared"} and "``" not in top  # every command module is listed
    assert f"Commands: {', '.join(commands)};" in description
    for command in commands:
        entries = option_entries(dwr_gym(command, "--help").stdout)
        assert all(text.count("(default:") <= 1 for text in entries.values()), command
    train = option_entries(dwr_gym("train", "--help").stdout)
    assert "a run directory (or a checkpoint .zip in one)" in train["--resume"]
    assert train["--run-dir"].count("runs/<algo>[-residual]-seed<seed>") == 1


# 7 and 17. Figures: the same bytes for the same inputs, at their stated size; a distinct colour and marker per
# policy, labelled reference lines, axis labels with quantity and unit, legends outside the data.


def check_figure(fig: object, path: Path) -> None:
    """What every figure owes its reader, as the issue lists it."""
    import re

    from PIL import Image

    with Image.open(path) as image:
        dpi, size = round(image.info["dpi"][0]), image.size
    assert size == tuple(round(inches * dpi) for inches in fig.get_size_inches()), path.name  # type: ignore[attr-defined]
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)  # a saved figure is closed: draw it again, laid out as it was saved
    canvas.draw()
    renderer = canvas.get_renderer()
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.lines]  # type: ignore[attr-defined]
    legends = [*fig.legends, *(ax.get_legend() for ax in axes if ax.get_legend())]  # type: ignore[attr-defined]
    legend_texts = {text.get_text() for legend in legends for text in legend.get_texts()}
    for ax in axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            assert re.fullmatch(r"\S.*\[.+\]", label), f"{path.name}: axis label {label!r} has no [unit]"
        for line in ax.lines:
            x, y = line.get_xdata(), line.get_ydata()
            reference = len(x) == 2 and ((x[0] == x[1] and list(y) == [0, 1]) or (y[0] == y[1] and list(x) == [0, 1]))
            if reference:
                assert not line.get_label().startswith("_") and line.get_label() in legend_texts, path.name
        box = ax.get_window_extent(renderer)
        for legend in legends:
            outer = legend.get_window_extent(renderer)
            overlap = min(box.x1, outer.x1) - max(box.x0, outer.x0), min(box.y1, outer.y1) - max(box.y0, outer.y0)
            assert min(overlap) <= 1.0, f"{path.name}: a legend lies over the data"
    for legend in legends:
        looks = [(h.get_color(), h.get_marker(), h.get_linestyle()) for h in legend.legend_handles]
        assert len(set(looks)) == len(looks), f"{path.name}: two legend entries look the same"


@pytest.fixture(scope="module")
def recorded() -> dict[str, object]:
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import default_agents, load_agent

    policies: dict[str, object] = dict(load_agent(path) for path in default_agents().values())
    policies.update({name: name for name in ("ptc", "conventional-ptc", "fabregas", "fixed-time", "astolfi",
                                             "pt-astolfi", "optimal", "robust-pt")})  # fmt: skip
    assert len(policies) == 13  # as compare draws them: every controller and shipped agent in one figure
    return evaluate(policies, make_scenario("paper-fig5"), record=True)  # type: ignore[arg-type]


def test_compare_figures_are_readable_and_byte_stable(recorded: dict[str, object], tmp_path: Path) -> None:
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import PRETRAINED
    from train.reporting.compare_figures import plot_learning_curves, plot_time_series, plot_trajectories

    labels = make_scenario("paper-fig5").labels
    for name, draw in (("time_series.png", lambda p: plot_time_series(recorded, p)),  # type: ignore[arg-type]
                       ("trajectories.png", lambda p: plot_trajectories(recorded, labels, p)),  # type: ignore[arg-type]
                       ("learning_curves.png", lambda p: plot_learning_curves(PRETRAINED, p))):  # fmt: skip
        check_figure(draw(tmp_path / name), tmp_path / name)
        draw(tmp_path / f"again_{name}")
        assert (tmp_path / name).read_bytes() == (tmp_path / f"again_{name}").read_bytes(), name
    text = (tmp_path / "learning_curves.png").read_bytes()
    assert b"Matplotlib" not in text  # no version in the metadata


def test_the_paper_robustness_and_learning_figures_are_readable(tmp_path: Path) -> None:
    from train.evaluation.reproduce import measure
    from train.reporting import learning_curves, paper
    from train.reporting.robustness_figures import plot_disturbance

    runs = measure(dt=0.05)
    for draw in (paper.figure5, paper.figure6, paper.figure7, paper.figure8, paper.figure9, paper.optimal_vs_ptc):
        path = tmp_path / f"{draw.__name__}.png"
        check_figure(draw(runs, path), path)  # type: ignore[arg-type]
    rows = json.loads((ROOT / "docs/robustness/robustness.json").read_text())
    path = tmp_path / "delay.png"
    check_figure(plot_disturbance([r for r in rows if r["disturbance"] == "delay"], "delay", path), path)
    curve = [{"round": r, **{f"{k}_T{T}": 0.5 + r / 10 for k in ("success", "heading", "energy") for T in (10, 20)}}
             for r in range(3)]  # fmt: skip
    check_figure(
        learning_curves.plot_dagger_curve(curve, (10.0, 20.0), tmp_path / "dagger.png"), tmp_path / "dagger.png"
    )
    runs_of = {seed: [{"timesteps": t, "return_mean": t / 1e3 + seed, "success_rate": 0.5} for t in (0, 1e3)]
               for seed in (0, 1)}  # fmt: skip
    groups = {f"c00{i}": {"hyperparams": {}, "runs": runs_of} for i in range(3)}
    path = tmp_path / "sweep.png"
    check_figure(learning_curves.plot_sweep_curves(groups, path, ("return_mean", "success_rate")), path)


def test_reproduce_tells_what_it_runs_as_it_goes(tmp_path: Path) -> None:
    process = subprocess.Popen([sys.executable, "-m", "train.cli", "reproduce", "--dt", "0.05", "--no-gif", "--out",
                                str(tmp_path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "MPLBACKEND": "Agg"})  # fmt: skip
    assert process.stdout is not None
    first = process.stdout.readline()
    running = process.poll() is None
    process.communicate(timeout=300)
    assert first.startswith("running Figure 5") and running  # printed while the work goes on, not at the end
    assert process.returncode == 0


# 8-11. What the table and the errors say.


def test_the_T_con_column_shows_the_prescribed_time_asked_for(tmp_path: Path) -> None:
    result = dwr_gym("evaluate", "--controllers", "ptc", "--scenarios", "random", "--n", "3", "--T-con", "0.5",
                     "--optimum", "none", "--no-progress", "--out", str(tmp_path))  # fmt: skip
    assert result.returncode == 0, result.stderr
    block = result.stdout.split("random, T_con = 0.5 s", 1)[1].splitlines()
    header, row = block[1].split(), block[3].split()
    assert row[header.index("T_con")] == "0.5"


@pytest.mark.parametrize(
    "args, message",
    [
        (["evaluate", "--n", "-5"], "--n -5 is invalid: expected an integer in [1, 1e7]"),
        (["evaluate", "--n", "0"], "--n 0 is invalid: expected an integer in [1, 1e7]"),
        (["robustness", "--n", "-5"], "--n -5 is invalid: expected an integer in [1, 1e7]"),
        (["evaluate", "--env-kwargs", "T_con=nan"], "T_con=nan is invalid (not finite): expected a finite number"),
        (["evaluate", "--env-kwargs", "T_con=inf"], "T_con=inf is invalid (not finite)"),
        (["evaluate", "--agents", "README.md"], "agent 'README.md' is invalid: it is not a model .zip"),
        (["compare", "--agents", "README.md"], "agent 'README.md' is invalid: it is not a model .zip"),
    ],
)
def test_bad_input_names_what_the_user_typed(args: list[str], message: str) -> None:
    result = dwr_gym(*args, cwd=ROOT)
    assert result.returncode == 2 and message in result.stderr and len(result.stderr.strip().splitlines()) == 1


def test_a_model_zip_outside_a_run_is_named_itself(tmp_path: Path) -> None:
    import shutil

    shutil.copy(ROOT / "train/pretrained/ppo/model.zip", tmp_path / "model.zip")
    result = dwr_gym("evaluate", "--agents", str(tmp_path / "model.zip"), cwd=tmp_path)
    assert result.returncode == 2
    assert f"agent {str(tmp_path / 'model.zip')!r} is invalid: no config.yaml beside it or above it" in result.stderr


# 12-14. Extras, headless machines, what is registered.


def run_python(code: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=ROOT,
                          env=env if env is not None else dict(os.environ))  # fmt: skip


def test_the_sb3_adapter_without_the_train_extra_says_what_to_install() -> None:
    result = run_python("import sys; sys.modules['stable_baselines3'] = None; from dwr_gym.sb3 import make_sb3_vec_env")
    assert result.returncode == 1
    assert result.stderr.strip().splitlines()[-1].endswith('pip install "dwr-gym[train]"')


def test_check_env_on_a_headless_machine_prints_nothing_from_sdl() -> None:
    quiet = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "XDG_RUNTIME_DIR",
                                                                "SDL_VIDEODRIVER", "SDL_AUDIODRIVER")}  # fmt: skip
    code = ("import gymnasium as gym, dwr_gym\nfrom gymnasium.utils.env_checker import check_env\n"
            "check_env(gym.make('DWRPointStabilization-v1').unwrapped)\n")  # fmt: skip
    result = run_python(code, quiet)
    assert result.returncode == 0, result.stderr
    assert "XDG_RUNTIME_DIR" not in result.stderr + result.stdout and "pygame" not in result.stdout


def test_info_lists_every_registered_env_and_the_unknown_keyword_error_lists_every_keyword() -> None:
    result = dwr_gym("info")
    assert result.returncode == 0, result.stderr
    for env_id in (HELD_ENV_ID, TASK_ENV_ID, PAPER_ENV_ID, "DWRPointStabilizationGoal-v0"):
        assert f"  {env_id}  " in result.stdout
    assert f"defaults of {DEFAULT_ENV_ID}" in result.stdout and "hold_to_T_con = True" in result.stdout
    assert "T_con_range = (10.0, 60.0)" in result.stdout and "T_con_range = (10.0, 60.0)" in result.stdout
    wrong = dwr_gym("evaluate", "--env-kwargs", "T_conn=3")
    allowed = wrong.stderr.split("allowed: ", 1)[1].strip().split(", ")
    assert {"robot", "wheel_saturation", "disturbances", "T_con"} <= set(allowed)


# 15. A law that fails by design is explained once.


def test_fabregas_is_explained_once(tmp_path: Path) -> None:
    result = dwr_gym("evaluate", "--controllers", "fabregas", "ptc", "--scenarios", "paper-fig5", "random", "--n", "5",
                     "--env", PAPER_ENV_ID, "--optimum", "none", "--no-progress", "--out", str(tmp_path))  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("slow law of ref. [9]") == 1


# 18. The test run warns only where a warning is what a test tests: here, v0's.


def test_v0_and_v1_warn_that_they_are_out_of_date_and_v2_does_not() -> None:
    """Gymnasium's versioning: an id with a newer version warns (v0 and v1 since v2 exists); the newest does not."""
    import warnings

    import gymnasium as gym

    with pytest.warns(DeprecationWarning, match="DWRPointStabilization-v0 is out of date"):
        gym.make(PAPER_ENV_ID)
    with pytest.warns(DeprecationWarning, match="DWRPointStabilization-v1 is out of date"):
        gym.make(TASK_ENV_ID)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym.make("DWRPointStabilization-v2")
