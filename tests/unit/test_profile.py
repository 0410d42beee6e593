"""The robot's profile: roles matched on a graph by type, then by name; a profile file fixes
what matching cannot know; the shipped profiles; one-line errors for a bad file."""

from __future__ import annotations

import pytest

from astiop.ros2.catalog import astibot_catalog
from astiop.ros2.profile import match_profile
from astiop.ros2.profile_file import ProfileError, parse, read_spec, shipped_names, write_profile
from astiop.ros2.profile_types import normalise_namespace
from astiop.transports.live_catalog import describe_graph, nothing_listed

# A TurtleBot3 Burger under Nav2 on Jazzy, the parts of its graph that matter here (beside the
# names that could be taken for a role: Nav2's other velocities, costmaps, plans and poses)
TB3_TOPICS = [
    ("/amcl_pose", "geometry_msgs/msg/PoseWithCovarianceStamped"),
    ("/battery_state", "sensor_msgs/msg/BatteryState"),
    ("/cmd_vel", "geometry_msgs/msg/TwistStamped"),
    ("/cmd_vel_nav", "geometry_msgs/msg/TwistStamped"),
    ("/cmd_vel_smoothed", "geometry_msgs/msg/TwistStamped"),
    ("/global_costmap/costmap", "nav_msgs/msg/OccupancyGrid"),
    ("/goal_pose", "geometry_msgs/msg/PoseStamped"),
    ("/initialpose", "geometry_msgs/msg/PoseWithCovarianceStamped"),
    ("/local_costmap/costmap", "nav_msgs/msg/OccupancyGrid"),
    ("/local_plan", "nav_msgs/msg/Path"),
    ("/map", "nav_msgs/msg/OccupancyGrid"),
    ("/odom", "nav_msgs/msg/Odometry"),
    ("/plan", "nav_msgs/msg/Path"),
    ("/scan", "sensor_msgs/msg/LaserScan"),
    ("/tf", "tf2_msgs/msg/TFMessage"),
]
TB3_ACTIONS = [
    ("/navigate_through_poses", "nav2_msgs/action/NavigateThroughPoses"),
    ("/navigate_to_pose", "nav2_msgs/action/NavigateToPose"),
]
TB3_NODES = ["/amcl", "/bt_navigator", "/controller_server", "/map_server", "/turtlebot3_node"]


def tb3_graph(namespace: str = "", **drop: bool):
    lists = nothing_listed()
    lists["topic"] = [(namespace + n, t) for n, t in TB3_TOPICS if not drop.get(n[1:])]
    lists["action"] = [(namespace + n, t) for n, t in TB3_ACTIONS]
    lists["service"] = [(namespace + "/amcl/get_parameters", "rcl_interfaces/srv/GetParameters")]
    lists["node"] = [(namespace + n, "") for n in TB3_NODES]
    return describe_graph(lists)


def test_the_astibot_plays_every_role_under_its_own_names():
    profile = match_profile(astibot_catalog())
    # /map is published beside the catalog (the backends watch it on its own)
    assert profile.make == "astibot" and profile.missing() == ["map"]
    assert profile.name("pose") == "/robot_pose" and profile.name("battery") == "/battery_status"
    assert (
        profile.name("navigation") == "/goto_position" and profile.kind("navigation") == "service"
    )
    assert profile.name("stop") == "/stop" and profile.units.battery_percentage == "fraction"
    assert profile.limits.max_linear_speed == 1.4  # the base's top; the settings say 0.8


def test_a_turtlebot3_under_nav2_is_matched_by_type_then_name():
    profile = match_profile(tb3_graph())
    assert profile.make == "turtlebot3_burger"
    expect = {
        "pose": "/amcl_pose",  # not /initialpose, nor the odometry origin
        "odometry": "/odom",
        "battery": "/battery_state",
        "scan": "/scan",
        "map": "/map",  # not a costmap
        "velocity_command": "/cmd_vel",  # not Nav2's own /cmd_vel_nav
        "navigation": "/navigate_to_pose",
        "plan": "/plan",
    }
    assert {r: profile.name(r) for r in expect} == expect
    assert profile.kind("navigation") == "action"
    assert profile.matches["velocity_command"].type == "geometry_msgs/msg/TwistStamped"
    assert {"stop", "dock", "undock", "status", "save_location"} <= set(profile.missing())
    assert profile.units.battery_percentage == "percent" and profile.limits.max_linear_speed == 0.22
    assert "/odom" not in profile.state_topics() or profile.name("odometry") == "/odom"


def test_the_pose_falls_back_to_odometry_and_says_so():
    profile = match_profile(tb3_graph(amcl_pose=True, tf=True))  # no amcl, no /tf
    assert profile.name("pose") == "/odom"
    assert "for want of a Pose2D" in profile.matches["pose"].why


def test_a_namespace_holds_the_robot_and_nothing_outside_it():
    profile = match_profile(tb3_graph("/tb3_1"), read_spec("auto", "tb3_1/"))
    assert profile.namespace == "/tb3_1"
    assert profile.name("battery") == "/tb3_1/battery_state"
    assert profile.name("velocity_command") == "/tb3_1/cmd_vel"
    other = match_profile(tb3_graph("/tb3_2"), read_spec("auto", "/tb3_1"))
    assert other.name("battery") is None and "battery" in other.missing()


def test_a_profile_file_fixes_names_units_and_limits(tmp_path):
    f = tmp_path / "bot.toml"
    f.write_text(
        '[robot]\nmake = "mybot"\n[roles]\nbattery = "/power/state"\ndock = ""\n'
        '[units]\nbattery_percentage = "percent"\n[limits]\nmax_linear_speed = 0.5\n'
    )
    profile = match_profile(tb3_graph(), read_spec(str(f)))
    assert profile.make == "mybot" and profile.source == str(f)
    assert profile.name("battery") == "/power/state"
    assert "not on the graph yet" in profile.matches["battery"].why
    assert profile.name("dock") is None and "none, says" in profile.matches["dock"].why
    assert profile.name("scan") == "/scan"  # the rest is still matched
    assert profile.limits.max_linear_speed == 0.5 and profile.units.battery_percentage == "percent"


def test_a_written_profile_reads_back_as_the_same_profile(tmp_path):
    first = match_profile(tb3_graph("/tb3_1"), read_spec("auto", "/tb3_1"))
    f = tmp_path / "tb3.toml"
    f.write_text(write_profile(first))
    again = match_profile(tb3_graph("/tb3_1"), read_spec(str(f)))
    assert {r: again.name(r) for r in first.matches} == {r: first.name(r) for r in first.matches}
    assert again.units == first.units and again.limits == first.limits
    assert again.map_name == first.map_name == "turtlebot3_burger" and not again.map.geofence


def test_a_robots_places_belong_to_its_map_and_its_geofence_is_the_profiles(tmp_path):
    assert match_profile(astibot_catalog()).map_name == "warehouse"  # the seeded places' map
    tb3 = match_profile(tb3_graph())
    assert tb3.map_name == "turtlebot3_burger" and tb3.map.geofence is None  # its /map's extent
    f = tmp_path / "site.toml"
    f.write_text('[map]\nname = "hall_b"\ngeofence = [-2, -2.5, 2, 2.5]\n')
    site = match_profile(tb3_graph(), read_spec(str(f)))
    assert site.map_name == "hall_b" and site.map.geofence == (-2.0, -2.5, 2.0, 2.5)
    assert site.as_dict()["map"] == {"name": "hall_b", "geofence": [-2.0, -2.5, 2.0, 2.5]}


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("[robot\n", "not TOML"),
        ("[wheels]\n", "unknown section [wheels]"),
        ('[roles]\nbatery = "/b"\n', "unknown key roles.batery"),
        ('[roles]\nbattery = "b"\n', "a name starts with /"),
        ('[units]\nbattery_percentage = "volts"\n', "fraction or percent"),
        ("[limits]\nmax_linear_speed = -1\n", "must be above 0"),
        ('[limits]\nradius = "big"\n', "is a number"),
        ('[robot]\nnamespace = "9bad"\n', "not a ROS 2 namespace"),
        ('[map]\nname = "hall b"\n', "map.name is 1-64 letters"),
        ("[map]\ngeofence = [0, 0, 5]\n", "map.geofence is [x_min"),
        ("[map]\ngeofence = [5, 0, 1, 4]\n", "min below max"),
        ("[map]\nfence = 1\n", "unknown key map.fence"),
    ],
)
def test_a_bad_profile_file_is_said_in_one_line(text, says):
    with pytest.raises(ProfileError, match=None) as err:
        parse(text, "bot.toml")
    assert says in str(err.value) and "\n" not in str(err.value)


def test_a_missing_profile_names_the_shipped_ones(tmp_path):
    with pytest.raises(ProfileError) as err:
        read_spec(str(tmp_path / "nope.toml"))
    assert "turtlebot3_burger" in str(err.value)
    assert {"astibot", "turtlebot3_burger", "turtlebot3_waffle"} <= set(shipped_names())


def test_namespaces_are_checked():
    assert normalise_namespace("tb3_1/") == "/tb3_1" and normalise_namespace("/") == ""
    with pytest.raises(ValueError):
        normalise_namespace("/tb 3")


def test_the_state_reads_each_role_in_its_own_units():
    import math

    from astiop.transports.state import from_messages

    profile = match_profile(tb3_graph())
    amcl = {"pose": {"pose": {"position": {"x": 1.5, "y": -0.5}, "orientation": {"w": 1.0}}}}
    odom = {
        "pose": {"pose": {"position": {"x": 0.1, "y": 0.0}, "orientation": {"w": 1.0}}},
        "twist": {"twist": {"linear": {"x": 0.2}, "angular": {"z": 0.1}}},
    }
    battery = {"percentage": 77.775, "voltage": 12.1, "current": -0.5, "power_supply_status": 2}
    scan = {"angle_min": 0.0, "angle_increment": 0.5, "range_min": 0.12, "range_max": 3.5,
            "ranges": [0.0, 0.05, 1.25, 4.0, float("nan")]}  # fmt: skip
    msgs = {"/amcl_pose": amcl, "/odom": odom, "/battery_state": battery, "/scan": scan}
    st = from_messages(0.0, msgs, profile=profile)
    assert (st.pose.x, st.pose.y) == (1.5, -0.5), "the map pose, not the odometry origin"
    assert st.velocity == (0.2, 0.0, 0.1)
    assert st.battery.percentage == 0.77775  # 0-100 on a TurtleBot3: 77.8 %, not 7777.5 %
    # no return (0.0, under range_min, over range_max, NaN) is not an obstacle at 0 m
    assert [math.isinf(r) for r in st.scan.ranges] == [True, True, False, True, True]
    assert st.status is None and st.state_word == "unknown"
    without_amcl = from_messages(0.0, {"/odom": odom}, profile=profile)
    assert without_amcl.pose is None, "a silent map pose is not replaced by odometry's origin"


def test_an_unsaid_battery_scale_reads_a_percentage_over_one_as_percent():
    from astiop.transports.state import battery_fraction

    assert battery_fraction(0.85, None) == 0.85 and battery_fraction(85.0, None) == 0.85
    assert (
        battery_fraction(0.85, "percent") == 0.0085 and battery_fraction(0.85, "fraction") == 0.85
    )


def test_the_rules_plan_in_the_robots_own_names():
    from astiop.agent.intent import classify
    from astiop.agent.rules import plan_intents
    from astiop.robot.safety import always_allowed
    from astiop.ros2.validation import validate

    profile = match_profile(tb3_graph())

    def plan(request: str) -> list[str]:
        return plan_intents(classify(request, ["bench"]), profile, {"bench": (1.0, 0.5)}.get)

    assert plan("where is the robot?") == ["ros2 topic echo /amcl_pose --once"]
    assert plan("what is the battery level?") == ["ros2 topic echo /battery_state --once"]
    assert plan("is anything in front of the robot?") == ["ros2 topic echo /scan --once"]
    (goal,) = plan("go to x 1.0 y 0.5")
    assert goal.startswith(
        "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose"
    )
    assert "position: {x: 1.000, y: 0.500}" in goal and "frame_id: map" in goal
    assert plan("go to bench") == [goal]  # a named place by its coordinates
    # no stop service: its Nav2 goals cancelled (a zero Twist alone, Nav2 drives on), then still
    cancel, stop = plan("stop the robot")
    assert cancel == (
        'ros2 service call /navigate_to_pose/_action/cancel_goal action_msgs/srv/CancelGoal "{}"'
    )
    assert stop.startswith("ros2 topic pub --once /cmd_vel geometry_msgs/msg/TwistStamped")
    checked = validate(cancel, tb3_graph())  # the action's hidden service, always allowed
    assert checked.valid and checked.kind == "actuate" and always_allowed(checked)
    assert checked.message["goal_info"]["goal_id"]["uuid"] == [0] * 16  # every goal
    assert not validate(cancel.replace("navigate_to_pose", "spin"), tb3_graph()).valid
    assert plan("dock the robot") == []  # it has no dock: nothing rather than a guess


def test_a_place_the_robots_map_does_not_hold_is_said_so_not_guessed(tmp_path):
    from astiop.agent.intent import classify
    from astiop.agent.local_save import unknown_place
    from astiop.store import Store

    store = Store(tmp_path / "a.db")
    store.use_map("turtlebot3_burger", None)
    store.add_location("bench", 1.0, 0.5)
    tb3 = match_profile(tb3_graph())

    def said(request: str, profile=tb3):
        return unknown_place(request, classify(request, ["bench"]), profile, store)

    answer = said("go to shipping")
    assert answer.startswith("There is no place named 'shipping' on this robot's map")
    assert (
        "(turtlebot3_burger); its places: bench (other maps hold places too: warehouse)." in answer
    )
    assert said("drive to the loading bay.").count("'loading bay'") == 1
    assert said("go to bench") is None and said("go to x 1.0 y 0.5") is None
    # the ASTIbot looks names up itself (/goto_position by name): the robot answers
    assert said("go to shipping", match_profile(astibot_catalog())) is None
    store.close()


def test_a_question_the_robot_has_no_reading_for_is_answered_so():
    from astiop.agent.intent import classify
    from astiop.agent.roles import nothing_to_read

    no_battery = match_profile(tb3_graph(battery_state=True))
    said = nothing_to_read(classify("what is the battery level?", []), no_battery)
    assert said.startswith("This robot publishes no battery state")
    # a question it can answer, or one part of it: not this answer
    assert nothing_to_read(classify("where is the robot?", []), no_battery) is None
    assert (
        nothing_to_read(classify("what is the battery level?", []), match_profile(tb3_graph()))
        is None
    )


def test_the_models_tools_are_the_robots_roles():
    from astiop.agent.tools import build_tools, render

    cat = tb3_graph()
    tools = {t.id: t for t in build_tools(cat, ["bench"])}
    assert tools["battery"].command == "ros2 topic echo /battery_state --once"
    assert tools["where"].command == "ros2 topic echo /amcl_pose --once"
    assert "strafe_left" not in tools and "bench" not in tools  # a Nav2 base goes by x, y
    assert "/cmd_vel_nav" not in str(tools) and "/global_costmap/costmap" not in str(tools)
    goal = render({"tool": "drive_xy", "x": 1, "y": 0.5}, list(tools.values()))
    assert goal.startswith("ros2 action send_goal /navigate_to_pose")


def test_a_reading_is_said_in_its_roles_units():
    from astiop.agent.summaries import summarize
    from astiop.transports.base import Execution

    battery = {"percentage": 77.775, "voltage": 12.1, "current": -0.5, "power_supply_status": 2}
    ex = Execution("ros2 topic echo /battery_state --once", True, executed=True, values=battery,
                   role="battery", units="percent")  # fmt: skip
    assert "battery 77.8 %" in summarize(ex)
    scan = {"angle_min": 0.0, "angle_increment": 0.5, "range_min": 0.12, "range_max": 3.5,
            "ranges": [0.0, 0.05, 1.25, 4.0]}  # fmt: skip
    ex = Execution("ros2 topic echo /scan --once", True, executed=True, values=scan, role="scan")
    assert "nearest return 1.25 m" in summarize(ex)


def test_a_misspelt_reading_is_never_offered_a_name_that_moves_the_robot():
    from astiop.ros2.validation import validate

    cat = tb3_graph()
    r = validate("ros2 topic echo /robot_pose --once", cat)
    assert not r.valid and "/goal_pose" not in r.reason, r.reason
    ns = tb3_graph("/tb3_1")
    ns.profile = match_profile(ns, read_spec("auto", "/tb3_1"))
    pub = validate(
        'ros2 topic pub --once /tb3_1/cmd_vel geometry_msgs/msg/TwistStamped "{twist: {linear: {x: 0.1}}}"',
        ns,
    )
    assert pub.valid and pub.kind == "actuate", pub.reason  # its velocity, under its namespace


def test_every_state_topic_of_a_turtlebot3_can_be_recorded():
    """The recording writes each state topic with its ros2msg schema: a type astiop has no
    definition for would fail every poll of that topic (a TurtleBot3's /amcl_pose did)."""
    from astiop.recording.schemas import ros2msg

    profile = match_profile(tb3_graph())
    types = {profile.matches[r].type for r in profile.matches if profile.matches[r].kind == "topic"}
    recorded = {t for n, t in TB3_TOPICS if n in profile.state_topics()}
    assert "geometry_msgs/msg/PoseWithCovarianceStamped" in recorded and recorded <= types
    for type_name in recorded:
        assert "\nMSG: " in ros2msg(type_name)  # its definition, and each type it uses


def test_a_robot_that_takes_goals_on_a_topic_is_sent_them_there_and_fenced():
    """A navigator with /goal_pose and no action (the issue's third way to navigate)."""
    from astiop.agent.gate import action_of
    from astiop.agent.intent import classify
    from astiop.agent.rules import plan_intents
    from astiop.robot.safety import SafetyPolicy
    from astiop.ros2.validation import validate

    catalog = tb3_graph()
    catalog.profile = match_profile(catalog, parse('[roles]\nnavigation = "/goal_pose"\n', "f"))
    (goal,) = plan_intents(classify("go to x 5 y 6", []), catalog.profile)
    assert goal.startswith("ros2 topic pub --once /goal_pose geometry_msgs/msg/PoseStamped")
    checked = validate(goal, catalog)
    assert checked.valid and checked.kind == "actuate"
    assert action_of(checked).kind == "navigate" and action_of(checked).xy == (5.0, 6.0)
    fence = SafetyPolicy(geofence=(0.0, 0.0, 10.0, 10.0))
    assert fence.review(checked, False).allowed
    far = validate(goal.replace("x: 5.000", "x: 55.000"), catalog)
    assert "outside the geofence" in fence.review(far, False).reason
    odom = validate(goal.replace("frame_id: map", "frame_id: odom"), catalog)
    assert "map frame" in fence.review(odom, False).reason
    from astiop.agent.goals import started, started_word
    from astiop.transports.base import Execution

    sent = Execution(goal, True, kind="actuate", executed=True)
    assert started(sent)  # followed to arrival
    assert started_word(sent) == "goal sent"  # a topic answers nothing: never "accepted"


def test_a_pose_told_to_the_localiser_is_never_a_stop_and_is_fenced():
    """amcl's /initialpose (a PoseWithCovarianceStamped with no twist): not taken for a stop by
    the intent gate, and fenced and held to the map frame like a goal; with no geofence known,
    every goal is refused."""
    from astiop.agent.gate import action_of, check
    from astiop.agent.intent import Intent
    from astiop.robot.safety import SafetyPolicy
    from astiop.ros2.catalog import TopicSpec
    from astiop.ros2.validation import validate

    catalog = tb3_graph()
    catalog.topics["/initialpose"] = TopicSpec(
        "/initialpose", "geometry_msgs/msg/PoseWithCovarianceStamped", 0, "", subscriber="amcl"
    )
    far = validate(
        "ros2 topic pub --once /initialpose geometry_msgs/msg/PoseWithCovarianceStamped "
        '"{header: {frame_id: map}, pose: {pose: {position: {x: 30.0, y: 1.0}, '
        'orientation: {w: 1.0}}}}"',
        catalog,
    )
    assert far.valid and action_of(far).kind == "configure"
    assert check([Intent("stop")], [(far.text, action_of(far))], {}) is not None
    fence = SafetyPolicy(geofence=(0.0, 0.0, 10.0, 10.0))
    assert "outside the geofence" in fence.review(far, False).reason
    goal = validate(
        "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
        '"{pose: {header: {frame_id: map}, pose: {position: {x: 1.0, y: 1.0}}}}"',
        catalog,
    )
    assert fence.review(goal, False).allowed
    unknown = SafetyPolicy(geofence=None).review(goal, False)
    assert not unknown.allowed and "no geofence is known" in unknown.reason
