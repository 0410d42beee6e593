"""Key press to robot, and the console's cost, on both ROS 2 transports side by side.

    python benchmarks/ros2_latency.py [--repeats 3] [--latency-ms 300] [--cpu-s 10] [--domain 87]
                                      [--kinds sim,rclpy,cli]

One run measures, each repeat in fresh processes:
- rclpy: the console (--robot ros2 --ros2-transport rclpy) against `astiop sim node` (the
  simulator as real ROS 2 nodes); each Twist's arrival is taken at the robot's side by
  tests/cmd_vel_probe.py, a process of its own subscribed to /cmd_vel;
- cli: the console (--ros2-transport cli) against the emulated `ros2` executable
  (tests/emulator.py), which pays `--latency-ms` of start-up on every call, as importing rclpy
  and ros2cli does; the emulated robot logs each Twist's arrival;
- sim: the console on the built-in simulator, for the CPU reference only.
rclpy runs the wait-set executor, Humble's, on every distro (astiop/transports/rclpy/node.py).
time.monotonic() is system-wide on Linux, so the robot's clock and the console's agree.

Rows, after the robot is undocked: E-STOP (ctrl+e, while `w` is held) -> zero Twist at the
robot, and again in a new console before any teleop key; teleop (F5, `w`) first key -> first
Twist, once the robot's side sees the console's publisher (TELEOP_FIRST_KEYS times, each after
the last one's command lapsed), and the very first key after start-up; the worst gap between
Twists while `w` is pressed every 50 ms (beside the worst gap between the benchmark's own
presses: a loaded machine makes them late); the wall time of `gateway.run(...)` for
`ros2 topic echo ... --once` and `ros2 service call /stop` (warm: the console is up; each at a
random moment, as an operator types); the console's CPU (time.process_time(), and for the CLI
with its `ros2` subprocesses) over --cpu-s with the dashboard live and nothing pressed, from
AT_REST_S after the robot came to rest, as % of one core. It ends with a Markdown table: median
/ worst over the repeats, and the load average at each trial's start and during each CPU
window (the figures are only as quiet as the machine).

Keys are posted to the app as a terminal's driver posts them, not with Pilot.press, which waits
for the process to fall idle (up to 2 s a key on a console that receives its robot's topics).

DDS stays on the loopback: this sets ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and
ROS_LOCALHOST_ONLY=1 for itself and every process it starts, and ROS_DOMAIN_ID to --domain
(else the environment's ROS_DOMAIN_ID, else 87), before anything imports rclpy.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import random
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HELD_PRESSES = 40  # 2 s of a held key
KEY_REPEAT_S = 0.05  # a terminal's key repeat
EXEC_REPEATS = 3  # each exec row, per repeat
TELEOP_FIRST_KEYS = 5  # the teleop first-key row, per repeat
AT_REST_S = 5.0  # the robot at rest this long before the CPU window (the rclpy transport
# watches /odom while the robot moves and for 2 s after: the window is the console at rest)
RESULT = "RESULT "  # the child's one line of results on stdout
KINDS = ("sim", "rclpy", "cli")
Arrivals = Callable[[], list[tuple[float, float]]]  # (time.monotonic(), linear.x) per Twist


def keep_dds_on_loopback(domain: int | None) -> int:
    """Before anything imports rclpy: DDS on 127.0.0.1 only, in a domain of our own."""
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ["ROS_LOCALHOST_ONLY"] = "1"
    if domain is None:
        domain = int(os.environ.get("ROS_DOMAIN_ID") or 87)
    os.environ["ROS_DOMAIN_ID"] = str(domain)
    return domain


def say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


# -- the robot's side ---------------------------------------------------------------------------
class Probe:
    """tests/cmd_vel_probe.py: /cmd_vel as another process on the robot's side receives it."""

    def __init__(self) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, str(ROOT / "tests" / "cmd_vel_probe.py")],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        self.twists: list[tuple[float, float]] = []
        self.publishers = 0
        self.ready = threading.Event()
        threading.Thread(target=self._read, name="probe", daemon=True).start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            m = json.loads(line)
            if "mono" in m:
                self.twists.append((m["mono"], m["x"]))
            elif "publishers" in m:
                self.publishers = m["publishers"]
            elif m.get("ready"):
                self.ready.set()

    def arrivals(self) -> list[tuple[float, float]]:
        return list(self.twists)

    def close(self) -> None:
        self.proc.stdin.close()  # the probe ends when its stdin does
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5)


def emulated_arrivals(robot: Path) -> Arrivals:
    from tests.emulator import cmd_vel_received

    return lambda: [(m["mono"], m["twist"]["linear"]["x"]) for m in cmd_vel_received(robot)]


def armed_stop_up(robot: Path, latency_ms: int) -> bool:
    """The CLI transport's zero-Twist publisher is past its start-up, waiting on stdin."""
    from tests.emulator import ARMED_ESTOP, ros2_log

    armed = [e for e in ros2_log(robot) if e["argv"] == ARMED_ESTOP]
    return bool(armed) and time.monotonic() > armed[-1]["mono"] + latency_ms / 1000


# -- waiting and measuring -----------------------------------------------------------------------
async def until(predicate: Callable[[], object], timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what}: not within {timeout:g} s")
        await asyncio.sleep(0.005)


def first_after(arrivals: Arrivals, t: float, moving: bool) -> float | None:
    """When the first Twist after `t` arrived: a moving one (x > 0) or a zero one."""
    return next((m for m, x in arrivals() if m >= t and (x > 0) == moving), None)


def lapsed(arrivals: Arrivals) -> bool:
    """The last Twist the robot got is a zero one: the teleop command has lapsed."""
    got = arrivals()
    return bool(got) and got[-1][1] == 0.0


def quiet(arrivals: Arrivals, seconds: float) -> bool:
    """Nothing arrived at the robot for `seconds` (an E-STOP's zero burst is over)."""
    got = arrivals()
    return not got or time.monotonic() - got[-1][0] > seconds


def descendants_cpu(owned: Callable[[str], bool]) -> dict[tuple[int, str], float]:
    """CPU seconds of each live descendant of this process whose command line `owned` picks,
    keyed by (pid, start time) so a reused pid is not mistaken for the old process."""
    tick = os.sysconf("SC_CLK_TCK")
    parent, cpu, cmd = {}, {}, {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            stat = Path(f"/proc/{d}/stat").read_text()
            cmd[int(d)] = Path(f"/proc/{d}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        fields = stat[stat.rfind(")") + 2 :].split()
        parent[int(d)] = int(fields[1])
        cpu[int(d)] = ((int(fields[11]) + int(fields[12])) / tick, fields[19])
    mine, frontier = set(), {os.getpid()}
    while frontier:
        frontier = {p for p, pp in parent.items() if pp in frontier} - mine
        mine |= frontier
    return {(p, cpu[p][1]): cpu[p][0] for p in mine if p in cpu and owned(cmd.get(p, ""))}


def children_rusage() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


async def cpu_window(seconds: float, owned: Callable[[str], bool] | None) -> tuple[float, float]:
    """This process's CPU over `seconds` with nothing pressed, as % of one core; and with the
    subprocesses it started (those `owned` picks) added."""
    kids0 = descendants_cpu(owned) if owned else {}
    reaped0 = children_rusage()
    wall0, cpu0 = time.monotonic(), time.process_time()
    await asyncio.sleep(seconds)
    wall, cpu = time.monotonic() - wall0, time.process_time() - cpu0
    kids = 0.0
    if owned:
        kids1 = descendants_cpu(owned)
        kids = sum(v - kids0.get(k, 0.0) for k, v in kids1.items())
        # those that ended in the window: counted whole by getrusage, less what came before it
        kids += children_rusage() - reaped0 - sum(v for k, v in kids0.items() if k not in kids1)
    return 100 * cpu / wall, 100 * (cpu + kids) / wall


def type_key(app, key: str) -> None:
    """The key as a terminal's driver hands it to the app, without Pilot.press's waits: those
    wait for the process to fall idle (textual/_wait.py wait_for_idle, up to 1 s, twice), which a
    console receiving its robot's topics never does, so each press would take 1-2 s."""
    from textual import events

    app.post_message(events.Key(key, key if len(key) == 1 else None))


def ms(seconds: float) -> float:
    return round(seconds * 1000, 2)


# -- one console session ---------------------------------------------------------------------------
@dataclass
class Side:
    """The robot a console is started on, and how the robot's side is watched."""

    robot: dict  # the settings' robot table
    arrivals: Arrivals | None = None  # None: no /cmd_vel watched (the CPU reference)
    ready_to_drive: Callable[[], bool] = lambda: True
    matched: Callable[[], bool] = lambda: True  # the robot's side sees the console's publisher
    owned: Callable[[str], bool] | None = None  # the console's subprocesses, by command line


def console(side: Side):
    from astiop.app import make_app
    from astiop.config import load_settings
    from astiop.store import Store

    cfg = load_settings({"llm": {"model": "rules"}, "robot": side.robot}, env={})
    return make_app(cfg, Store(Path(tempfile.mkdtemp(prefix="astiop-bench-")) / "bench.db"))


async def session(side: Side, cpu_s: float) -> dict:
    out: dict = {}
    arrivals = side.arrivals
    app = console(side)
    async with app.run_test(size=(120, 40)) as pilot:
        gw = app.services.gateway
        say(f"  console up: {gw.backend.label or gw.backend.name}")
        status = await until(lambda: gw.state().status, 60, "the robot's /robot_status")
        if status.docked:
            undock = await asyncio.to_thread(
                gw.run, "ros2 service call /undock std_srvs/srv/Trigger", confirm=lambda _c: True
            )
            if not undock.executed or undock.error:
                raise RuntimeError(f"undock: {undock.reason or undock.error}")

        def idle_undocked() -> bool:
            s = gw.state().status
            return s is not None and s.state == "idle" and not s.docked

        await until(idle_undocked, 120, "the robot idle and undocked")
        say("  undocked; console CPU with the dashboard live")

        await pilot.press("f1")
        await until(lambda: app.robot_state.status is not None, 10, "the dashboard's state")
        await asyncio.sleep(AT_REST_S)
        out["load_cpu_window"] = os.getloadavg()[0]
        out["cpu_pct"], out["cpu_with_children_pct"] = await cpu_window(cpu_s, side.owned)
        if arrivals is None:
            return out  # the simulator's console: the CPU reference only

        say("  exec, warm")
        for key, text in (
            ("echo_ms", "ros2 topic echo /battery_status --once"),
            ("echo_odom_ms", "ros2 topic echo /odom --once"),
            ("stop_ms", "ros2 service call /stop std_srvs/srv/Trigger"),
        ):
            out[key] = []
            for _ in range(EXEC_REPEATS):
                # at a random moment, as an operator types: back to back, each echo --once
                # would start just after a message and wait one whole period for the next
                await asyncio.sleep(random.uniform(0.0, 1.0))
                t0 = time.perf_counter()
                ex = await asyncio.to_thread(gw.run, text, confirm=lambda _c: True)
                out[key].append(ms(time.perf_counter() - t0))
                if not ex.executed or ex.error:
                    raise RuntimeError(f"{text}: {ex.reason or ex.error}")

        say("  teleop")
        await until(side.ready_to_drive, 30, "the transport ready to drive")
        await pilot.press("f5")
        await until(lambda: type(app.screen).__name__ == "TeleopScreen", 10, "the teleop screen")
        # the first key after start-up: the rclpy publisher is made by this press
        pressed = time.monotonic()
        type_key(app, "w")
        got = await until(lambda: first_after(arrivals, pressed, True), 10, "the first Twist")
        out["teleop_cold_ms"] = ms(got - pressed)
        await until(side.matched, 10, "the robot's side matched with the console's publisher")
        await until(lambda: lapsed(arrivals), 10, "the lapse's zero Twist")

        # first keys, each after the last one's command lapsed (the robot at rest)
        out["teleop_ms"] = []
        for _ in range(TELEOP_FIRST_KEYS - 1):
            await asyncio.sleep(random.uniform(0.2, 0.5))
            pressed = time.monotonic()
            type_key(app, "w")
            got = await until(
                lambda t=pressed: first_after(arrivals, t, True), 10, "the first Twist"
            )
            out["teleop_ms"].append(ms(got - pressed))
            await until(lambda: lapsed(arrivals), 10, "the lapse's zero Twist")
        await asyncio.sleep(random.uniform(0.2, 0.5))

        # the key held: a press every 50 ms; the first one is a first key too
        start = time.monotonic()
        presses = []
        for i in range(HELD_PRESSES):
            await asyncio.sleep(max(0.0, start + i * KEY_REPEAT_S - time.monotonic()))
            presses.append(time.monotonic())
            type_key(app, "w")
        got = await until(lambda: first_after(arrivals, start, True), 10, "the first Twist")
        out["teleop_ms"].append(ms(got - start))

        # E-STOP while the key is held: at its next repeat
        await asyncio.sleep(max(0.0, start + HELD_PRESSES * KEY_REPEAT_S - time.monotonic()))
        pressed = time.monotonic()
        type_key(app, "ctrl+e")
        got = await until(lambda: first_after(arrivals, pressed, False), 10, "the zero Twist")
        out["estop_ms"] = ms(got - pressed)
        held = [m for m, x in arrivals() if start <= m <= pressed and x > 0]
        gaps = [(b - a, a) for a, b in zip(held, held[1:])]
        out["held_gap_ms"] = ms(max(gaps)[0])
        out["held_twists"] = len(held)
        # the benchmark's own presses late (a loaded machine stalls the event loop) show here
        out["held_press_gap_ms"] = ms(max(b - a for a, b in zip(presses, presses[1:])))
        if max(gaps)[0] > 0.2:  # say what happened around it
            at = max(gaps)[1]
            near = [(round(1000 * (m - at)), x) for m, x in arrivals() if -0.3 < m - at < 1.5]
            keys = [round(1000 * (p - at)) for p in presses if -0.3 < p - at < 1.5]
            say(f"  worst gap at {1000 * (at - start):.0f} ms: Twists {near}; presses {keys}")
    return out


async def estop_first(side: Side) -> float:
    """A new console on the same robot: the E-STOP before any teleop key (the rclpy transport
    has made no /cmd_vel publisher yet)."""
    app = console(side)
    async with app.run_test(size=(120, 40)):
        gw = app.services.gateway
        await until(lambda: gw.state().status, 60, "the robot's /robot_status")
        await until(side.ready_to_drive, 30, "the transport ready to drive")
        await until(lambda: quiet(side.arrivals, 0.3), 10, "/cmd_vel quiet")
        pressed = time.monotonic()
        type_key(app, "ctrl+e")
        got = await until(lambda: first_after(side.arrivals, pressed, False), 10, "a zero Twist")
        return ms(got - pressed)


# -- one trial, in a process of its own --------------------------------------------------------------
def measure(side: Side, cpu_s: float) -> dict:
    out = asyncio.run(session(side, cpu_s))
    if side.arrivals is not None:
        say("  E-STOP in a new console, before any teleop")
        out["estop_first_ms"] = asyncio.run(estop_first(side))
    return out


def trial(kind: str, args: argparse.Namespace) -> dict:
    if kind == "sim":
        return measure(Side({"backend": "sim"}), args.cpu_s)
    if kind == "cli":
        from tests.emulator import emulated_robot

        with emulated_robot(latency_ms=args.latency_ms, speed=args.sim_speed) as robot:
            os.environ["PATH"] = f"{robot}{os.pathsep}{os.environ['PATH']}"
            os.environ["ROS_DISTRO"] = "jazzy"
            client = f"{robot}/ros2"  # the emulated executable: the console's subprocesses
            side = Side(
                {"backend": "ros2", "ros2_transport": "cli"},
                emulated_arrivals(robot),
                ready_to_drive=lambda: armed_stop_up(robot, args.latency_ms),
                owned=lambda cmdline: client in cmdline,
            )
            return measure(side, args.cpu_s)
    from tests.ros import sim_node

    with sim_node(speed=args.sim_speed):
        probe = Probe()
        try:
            if not probe.ready.wait(60):
                raise RuntimeError("tests/cmd_vel_probe.py did not start")
            side = Side(
                {"backend": "ros2", "ros2_transport": "rclpy"},
                probe.arrivals,
                matched=lambda: probe.publishers >= 1,
            )
            return measure(side, args.cpu_s)
        finally:
            probe.close()


def run_trial(kind: str, args: argparse.Namespace) -> dict:
    argv = [sys.executable, __file__, "--trial", kind, "--domain", str(args.domain)]
    argv += ["--latency-ms", str(args.latency_ms), "--cpu-s", str(args.cpu_s)]
    argv += ["--sim-speed", str(args.sim_speed)]
    load = os.getloadavg()[0]
    try:
        run = subprocess.run(argv, stdout=subprocess.PIPE, text=True, timeout=600)
    except subprocess.TimeoutExpired:
        return {"error": "the trial took over 600 s", "load_start": load}
    lines = [line for line in run.stdout.splitlines() if line.startswith(RESULT)]
    if not lines:
        return {"error": f"the trial printed no result (exit status {run.returncode})"}
    return {"load_start": load, **json.loads(lines[-1][len(RESULT) :])}


# -- the table ----------------------------------------------------------------------------------------
ROWS = [
    ("E-STOP key → zero Twist at the robot", "estop_ms", " ms", "≤ 5 ms", "worst", 5.0),
    ("E-STOP key in a new console, before any teleop key", "estop_first_ms", " ms", "", "",
     None),
    ("teleop first key → first Twist (publisher matched)", "teleop_ms", " ms", "≤ 5 ms median",
     "median", 5.0),
    ("teleop first key after start-up (cold)", "teleop_cold_ms", " ms", "", "", None),
    ("teleop held (key every 50 ms): worst gap", "held_gap_ms", " ms", "", "", None),
    ("(the benchmark's own key presses: worst gap)", "held_press_gap_ms", " ms", "", "", None),
    ("exec `ros2 topic echo /battery_status --once` (1 Hz)", "echo_ms", " ms", "≤ 50 ms",
     "median", 50.0),
    ("exec `ros2 topic echo /odom --once` (50 Hz)", "echo_odom_ms", " ms", "", "", None),
    ("exec `ros2 service call /stop std_srvs/srv/Trigger`", "stop_ms", " ms", "", "", None),
    ("console CPU, dashboard live (% of one core)", "cpu_pct", " %", "≤ the simulator console's",
     "median", "sim"),
    ("… with the console's `ros2` subprocesses", "cpu_with_children_pct", " %", "", "", None),
]  # fmt: skip


def values(results: list[dict], key: str) -> list[float]:
    out: list[float] = []
    for r in results:
        v = r.get(key)
        out += v if isinstance(v, list) else [v] if v is not None else []
    return out


def cell(vs: list[float], unit: str) -> str:
    if not vs:
        return "—"
    return f"{statistics.median(vs):.1f} / {max(vs):.1f}{unit}"


HEADS = {
    "rclpy": "rclpy (astiop sim node)",
    "cli": "cli (emulated, {latency} ms start-up)",
}


def table(results: dict[str, list[dict]], args: argparse.Namespace) -> str:
    ok = {k: [r for r in rs if "error" not in r] for k, rs in results.items()}
    sim_cpu = values(ok.get("sim", []), "cpu_pct")
    columns = [k for k in results if k != "sim"]
    heads = " | ".join(HEADS[k].format(latency=args.latency_ms) for k in columns)
    lines = [
        f"| row (median / worst, n per cell = {args.repeats} repeats × {EXEC_REPEATS} for exec"
        f" rows, × {TELEOP_FIRST_KEYS} for teleop first key) | {heads} | target (rclpy) |",
        "|---" * (len(columns) + 2) + "|",
    ]
    for name, key, unit, target, stat, limit in ROWS:
        rcl = values(ok.get("rclpy", []), key)
        verdict = ""
        if limit == "sim" and rcl and sim_cpu:
            met = statistics.median(rcl) <= statistics.median(sim_cpu)
            target = f"≤ the simulator console's ({statistics.median(sim_cpu):.1f} %)"
            verdict = " — met" if met else " — missed"
        elif limit not in (None, "sim") and rcl:  # "sim": no reference run, no verdict
            figure = statistics.median(rcl) if stat == "median" else max(rcl)
            verdict = " — met" if figure <= limit else " — missed"
        cells = " | ".join(cell(values(ok[k], key), unit) for k in columns)
        lines.append(f"| {name} | {cells} | {target}{verdict} |")
    loads = " | ".join(cell(values(ok[k], "load_cpu_window"), "") for k in columns)
    lines.append(f"| load average (1 min) at the CPU window | {loads} | |")
    if "sim" in results:
        pad = " |" * len(columns)
        lines.append(
            f"| console CPU on the built-in simulator (reference) | {cell(sim_cpu, ' %')}"
            f" (robot.backend = sim), load {cell(values(ok['sim'], 'load_cpu_window'), '')} |" + pad
        )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--latency-ms", type=int, default=300, help="the emulated ros2's start-up")
    ap.add_argument("--cpu-s", type=float, default=10.0, help="the CPU window, s")
    ap.add_argument("--sim-speed", type=float, default=1.0, help="the robots' simulated speed")
    ap.add_argument("--domain", type=int, default=None, help="ROS_DOMAIN_ID (default 87)")
    ap.add_argument(
        "--kinds", default="sim,rclpy,cli", help="the consoles measured, in this order each repeat"
    )
    ap.add_argument("--trial", choices=KINDS, help=argparse.SUPPRESS)
    args = ap.parse_args()
    args.domain = keep_dds_on_loopback(args.domain)
    sys.path.insert(0, str(ROOT))

    if args.trial:
        try:
            out = trial(args.trial, args)
        except Exception as exc:  # noqa: BLE001 - the parent reports it in the table
            out = {"error": f"{type(exc).__name__}: {exc}"}
        out["load_end"] = os.getloadavg()[0]
        print(RESULT + json.dumps(out), flush=True)
        return

    say(
        f"ROS_DOMAIN_ID={args.domain}, DDS on the loopback; {os.cpu_count()} cores, "
        f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}"
    )
    kinds = [k for k in args.kinds.split(",") if k]
    unknown = set(kinds) - set(KINDS)
    if unknown:
        ap.error(f"unknown kinds: {', '.join(sorted(unknown))} (known: {', '.join(KINDS)})")
    results: dict[str, list[dict]] = {k: [] for k in kinds}
    for i in range(args.repeats):
        for kind in kinds:  # interleaved: the machine's load falls on each
            say(f"repeat {i + 1}/{args.repeats}: {kind}")
            r = run_trial(kind, args)
            results[kind].append(r)
            say(f"  {json.dumps(r)}")
    print()
    print(table(results, args))
    print()
    for kind, rs in results.items():
        loads = [f"{r.get('load_start', float('nan')):.2f}" for r in rs]
        print(f"{kind}: load average (1 min) at each trial's start: {', '.join(loads)}")
        for r in rs:
            if "error" in r:
                print(f"{kind}: a trial failed: {r['error']}")


if __name__ == "__main__":
    main()
