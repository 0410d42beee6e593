import json
import time

from astiop.sim.runner import SimRunner
from astiop.sim.simulator import Simulator
from tests.cli_runner import run_cli


def astiop(*args):
    return run_cli(*args)


def test_sim_goto_json(tmp_path):
    out = astiop("--db", str(tmp_path / "t.db"), "sim", "goto", "inspection_zone_a", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["reached"] is True and data["error_m"] < 0.05
    assert data["final_pose"]["x"] == __import__("pytest").approx(15.0, abs=0.05)
    assert data["path_length_m"] > 10 and data["sim_s"] > 10


def test_sim_goto_bad_targets_exit_2(tmp_path):
    db = str(tmp_path / "t.db")
    for target in ("nowhere", "15,7", "60,5", "1,2,3,4", "a,b"):
        out = astiop("--db", db, "sim", "goto", target)
        assert out.returncode == 2, (target, out)
        assert len(out.stderr.strip().splitlines()) == 1


def test_sim_bench_json_has_the_figures():
    out = astiop("sim", "bench", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert set(data) == {
        "real_time_factor",
        "lidar_ms_mean",
        "plan_ms_mean",
        "plan_ms_max",
        "mission_sim_s",
        "mission_wall_s",
        "max_penetration_m",
        "reached_all",
    }
    assert data["reached_all"] is True and data["max_penetration_m"] < 0.01


def test_runner_thread_advances_at_about_real_time():
    sim = Simulator(seed=0)
    runner = SimRunner(sim, speed=2.0).start()
    time.sleep(0.5)
    runner.stop()
    # generous bounds: CI machines are busy; the point is it runs and is paced, not flat out
    assert 0.3 < sim.t < 3.0
