"""Run-time guards and checkpoints: a bad particle stops the run with a message naming step,
time, stage, particle and value, its state goes to failure.npz/.vtu and the last good
checkpoint stays intact; a run killed by a signal resumes to the same final state."""
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import yaml

from scenes import build, layer
from taichi_granular.output import read_frame, read_series
from taichi_granular.simulation import Simulation, SimulationError


def small_layer(**run):
    data = layer(height=0.02, length=0.04, tilt_deg=25.0)
    data["run"] = {"end_time": 0.004, "output_interval": 0.001, **run}
    data["render"] = {"frames": False}
    return data


@pytest.mark.parametrize("field, value, reason, stage", [
    ("velocity", np.nan, "non-finite", "stage symplectic_verlet of step {next}"),
    ("density", 1.0e4, "density outside the plausible band", "after step {next}"),
])
def test_a_bad_particle_stops_the_run_with_its_step_stage_and_value(tmp_path, field, value, reason, stage):
    data = small_layer(guard="stage" if stage.startswith("stage") else "step")
    sim = Simulation(build(data), out_dir=tmp_path)
    sim.run(end_time=0.001)  # first frames and checkpoint written
    stage = stage.format(next=sim.step_count + 1)  # the step that meets the bad value
    checkpoint = (tmp_path / "checkpoint.npz").read_bytes()
    target = sim.state.field(field)
    bad = target.to_numpy()
    bad[7] = value
    target.from_numpy(bad)
    with pytest.raises(SimulationError) as err:
        sim.run()
    text = str(err.value)
    for words in ("t = 0.001", stage, "particle 7 (block 'layer')", reason, field):
        assert words in text, (words, text)
    if stage.startswith("stage"):  # NaN velocity: the half step moved the particle to NaN
        assert "non-finite fields of this particle: " in text and "velocity" in text.split("fields")[-1]
    assert (tmp_path / "checkpoint.npz").read_bytes() == checkpoint  # the last good state
    failure = np.load(tmp_path / "failure.npz")
    assert failure["field/position"].shape[0] == sim.state.n_total
    assert (tmp_path / "failure.vtu").exists()


def test_a_run_killed_by_a_signal_resumes_to_the_uninterrupted_state(tmp_path):
    """SIGKILL arrives at whatever point of the run (file writes included); resuming from the
    checkpoint gives the final state of the run that was never stopped, bit for bit."""
    data = small_layer()
    data["run"].update(end_time=0.03, output_interval=0.002)
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    straight = Simulation(build(data), out_dir=tmp_path / "straight")
    straight.run()
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "taichi_granular", "run", str(path), "--out", str(out), "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        if (out / "checkpoint.npz").exists() and len(read_series(out)) >= 3:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    resumed = subprocess.run([sys.executable, "-m", "taichi_granular", "resume", str(out), "--quiet"],
                             capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    a = read_frame(read_series(tmp_path / "straight")[-1][1])
    b = read_frame(read_series(out)[-1][1])
    for name in ("position", "velocity", "pressure", "density"):
        assert np.array_equal(a[name], b[name]), name
    assert [t for t, _ in read_series(out)] == [t for t, _ in read_series(tmp_path / "straight")]


def test_a_guard_every_k_steps_names_the_steps_within_which_it_arose(tmp_path):
    """run.guard_every = 5: the bad particle, set after step 28, is found at step 30 (the next
    multiple of 5), and the message names steps 29-30 and how to pin the step down."""
    sim = Simulation(build(small_layer(guard_every=5)), out_dir=tmp_path)
    sim.run(max_steps=28)  # stops between frames: checked at 28 before its final frame
    assert sim.last_guarded == 28
    target = sim.state.field("density")
    bad = target.to_numpy()
    bad[7] = 1.0e4
    target.from_numpy(bad)
    with pytest.raises(SimulationError) as err:
        sim.run()
    text = str(err.value)
    for words in ("after step 30", "particle 7 (block 'layer')", "density outside the plausible band",
                  "checked every 5 steps: it arose within steps 29-30", "run.guard_every=1"):
        assert words in text, (words, text)


def test_guard_every_needs_the_step_guard():
    from taichi_granular.config import ConfigError

    with pytest.raises(ConfigError, match="run.guard_every"):
        build(small_layer(guard="stage", guard_every=3))
