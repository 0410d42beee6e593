"""The console's screens in one table: each one's mode name, its key and its title. The app's
modes and bindings, the command palette and the snapshot tests all read it, so a screen added
here has its key, its palette command and its snapshot together."""

from __future__ import annotations

from dataclasses import dataclass

from textual.screen import Screen

from astiop.screens.alerts import AlertsScreen
from astiop.screens.bench import BenchScreen
from astiop.screens.chat import ChatScreen
from astiop.screens.dashboard import DashboardScreen
from astiop.screens.fleet import FleetScreen
from astiop.screens.locations import LocationsScreen
from astiop.screens.logs import LogsScreen
from astiop.screens.teleop import TeleopScreen


@dataclass(frozen=True)
class ScreenEntry:
    mode: str  # the app's mode name: `switch_mode(mode)`
    key: str  # the key that shows it
    title: str  # in the footer and the palette
    screen: type[Screen]


SCREENS: tuple[ScreenEntry, ...] = (
    ScreenEntry("dashboard", "f1", "Dashboard", DashboardScreen),
    ScreenEntry("chat", "f2", "Chat", ChatScreen),
    ScreenEntry("logs", "f3", "Logs", LogsScreen),
    ScreenEntry("locations", "f4", "Locations", LocationsScreen),
    ScreenEntry("teleop", "f5", "Teleop", TeleopScreen),
    ScreenEntry("bench", "f6", "Bench", BenchScreen),
    ScreenEntry("fleet", "f7", "Fleet", FleetScreen),
    ScreenEntry("alerts", "f8", "Alerts", AlertsScreen),
)
