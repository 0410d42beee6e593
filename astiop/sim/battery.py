"""Two 12 V 22 Ah VRLA batteries in series: charge, terminal voltage, current."""

from __future__ import annotations

from dataclasses import dataclass

CAPACITY_AH = 22.0
BASE_LOAD_W = 32.0  # Jetson, lidar, camera, PLC and lamp
R_INTERNAL = 0.03  # ohm, the pack
CHARGE_CURRENT_A = 4.4  # 0.2 C bulk
FLOAT_V = 27.3
ABSORB_V = 28.8


def open_circuit_voltage(soc: float) -> float:
    # 11.8 V empty to 12.85 V full per 12 V block, resting
    return 2.0 * (11.8 + 1.05 * soc)


@dataclass
class Battery:
    soc: float = 0.85
    current: float = 0.0  # A, ROS convention: negative while discharging
    voltage: float = 0.0
    charging: bool = False

    def __post_init__(self) -> None:
        self.soc = min(max(self.soc, 0.0), 1.0)
        self.voltage = open_circuit_voltage(self.soc)

    def update(self, dt: float, motor_power_w: float, on_charger: bool) -> None:
        ocv = open_circuit_voltage(self.soc)
        if on_charger:
            # constant current, tapering above 90 % (absorption), a trickle when full
            taper = 1.0 if self.soc < 0.9 else max(0.05, (1.0 - self.soc) / 0.1)
            load_a = (BASE_LOAD_W + motor_power_w) / ocv
            self.current = CHARGE_CURRENT_A * taper
            net = self.current - load_a
            self.voltage = min(
                ABSORB_V,
                max(
                    FLOAT_V if self.soc >= 0.999 else 0.0,
                    ocv + self.current * R_INTERNAL + 1.6 * taper,
                ),
            )
            self.charging = self.soc < 0.999
        else:
            power = BASE_LOAD_W + motor_power_w
            # P = V·I with V = ocv - I·R, solved for I
            disc = ocv * ocv - 4.0 * R_INTERNAL * power
            amps = (ocv - disc**0.5) / (2.0 * R_INTERNAL) if disc > 0 else ocv / (2 * R_INTERNAL)
            self.current = -amps
            net = -amps
            self.voltage = ocv - amps * R_INTERNAL
            self.charging = False
        self.soc = min(1.0, max(0.0, self.soc + net * dt / 3600.0 / CAPACITY_AH))


@dataclass
class LipoBattery:
    """A small 3S Li-ion/LiPo pack (a TurtleBot3's 11.1 V, 1.8 Ah): the same readings as
    `Battery`, for another robot in the same warehouse."""

    soc: float = 0.9
    capacity_ah: float = 1.8
    base_load_w: float = 5.0  # the SBC, the OpenCR board and the lidar
    current: float = 0.0
    voltage: float = 0.0
    charging: bool = False

    def __post_init__(self) -> None:
        self.soc = min(max(self.soc, 0.0), 1.0)
        self.voltage = lipo_voltage(self.soc)

    def update(self, dt: float, motor_power_w: float, on_charger: bool) -> None:
        if on_charger and self.soc < 0.999:
            self.current = 0.5 * self.capacity_ah  # 0.5 C
            self.voltage = min(12.6, lipo_voltage(self.soc) + 0.3)
            self.charging = True
        else:
            self.current = -(self.base_load_w + motor_power_w) / max(self.voltage, 1.0)
            self.voltage = lipo_voltage(self.soc) + self.current * 0.05  # pack resistance 50 mΩ
            self.charging = False
        self.soc = min(1.0, max(0.0, self.soc + self.current * dt / 3600.0 / self.capacity_ah))


def lipo_voltage(soc: float) -> float:
    """Resting voltage of three cells in series: 3.3 V a cell empty to 4.2 V full."""
    return 3.0 * (3.3 + 0.9 * soc)
