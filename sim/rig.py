"""The one description of the simulated rig: frame, actuators, fabric, contact, solver, camera, fall rule and object."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from .objects import OBJECTS, ObjectSpec


@dataclass(frozen=True)
class Frame:
    """The module: actuators at its corners (±size_x/2, ±size_y/2), fabric frame origin at its centre."""
    size_x_m: float = 0.5        # [m] the paper's m (frame and actuator spacing along x)
    size_y_m: float = 0.5        # [m] the paper's n
    z0_m: float = 1.5            # [m] reference height: corners at a_i = 0 (paper)


@dataclass(frozen=True)
class Actuators:
    """Four vertical linear actuators; command a_i [m] lowers corner i (+ = down, PROTOCOL.md §5).

    Modelled as MuJoCo `pid` actuators (position input only) on vertical slide joints, with the
    setpoint rate-limited to the actuator's top speed (`slewmax`): a position servo that reaches a
    new command no faster than the motor can drive the belt.
    """
    range_m: float = 0.25                 # [m] travel each way from z0 (paper)
    motor_speed_rpm: float = 120.0        # [rev/min] RS Pro 834-7590, 12 V, no-load (paper)
    pulley_circumference_m: float = 0.10   # [m/rev] CALIBRATED (sim/README.md): e.g. a GT2 50-tooth pulley; not in the paper
    kp_n_per_m: float = 2000.0            # [N/m] servo stiffness (SIM-NOTES); the real loop is on the Uno
    damping_ratio: float = 1.0            # [-] servo damping as a fraction of critical (SIM-NOTES)
    carriage_mass_kg: float = 0.2         # [kg] GUESS: V-slot carriage plate, wheels and clamp; gravity-compensated

    @property
    def speed_m_per_s(self) -> float:
        """Top carriage speed [m/s]: motor speed x pulley circumference (0.08 m/s by default)."""
        return self.motor_speed_rpm / 60.0 * self.pulley_circumference_m


@dataclass(frozen=True)
class Fabric:
    """The polyester sheet: a MuJoCo flexcomp grid (dim 2, full dofs), welded at its four corners to the carriages."""
    size_m: float = 0.52                  # [m] side of the square sheet, CALIBRATED slack (sim/README.md): the paper's
                                          # simulation used 0.5 m, its hardware 0.6 m
    resolution: int = 15                  # [vertices per side] odd, so the alternating mesh is mirror-symmetric
    mass_kg: float = 0.05                 # [kg] GUESS (SIM-NOTES value): 0.6 x 0.6 m at ~140 g/m^2 polyester
    young_pa: float = 5e6                 # [Pa] GUESS (SIM-NOTES): sets bending stiffness with thickness
    poisson: float = 0.3                  # [-] GUESS (SIM-NOTES)
    thickness_m: float = 3e-4             # [m] GUESS (SIM-NOTES): typical woven polyester
    damping_s: float = 0.3                # [s] elastic (Rayleigh, stiffness-proportional) damping, GUESS: SIM-NOTES'
                                          # 0.01 leaves the hanging edges flapping for > 6 s; 0.3 settles in 1.5 s
    radius_m: float = 0.002               # [m] collision thickness of the triangles (SIM-NOTES)
    edge_solref: tuple[float, float] = (0.002, 1.0)  # [s, -] edge-length equality: time constant, damping ratio
                                                     # (SIM-NOTES: 0.4-1.5 % strain; default solref gave 8-12 %)
    edge_solimp: tuple[float, float, float] = (0.999, 0.9999, 0.001)  # [-, -, m] edge constraints' impedance d0,
                                          # dmax, width: polyester barely stretches; MuJoCo's default (0.9, 0.95) lets
                                          # each edge give ~50x more under load (sim/README.md, Calibration)
    corner_weld_solref: tuple[float, float] = (0.002, 1.0)  # [s, -] corner-to-carriage welds: MuJoCo's default
                                                            # (0.02 s) leaves the corners ~18 mm off; this, 0.3 mm

    def __post_init__(self) -> None:
        if self.resolution < 3 or self.resolution % 2 == 0:
            raise ValueError(f"fabric resolution must be odd and >= 3, got {self.resolution}")

    @property
    def spacing_m(self) -> float:
        """Distance [m] between neighbouring vertices."""
        return self.size_m / (self.resolution - 1)


@dataclass(frozen=True)
class Contact:
    """Object-fabric contact, written on both the fabric and the object's geom so MuJoCo's mixing changes nothing."""
    friction: tuple[float, float, float] = (0.5, 0.005, 0.0001)  # sliding [-], torsional [m], rolling [m];
                                                                  # GUESS 0.5 (SIM-NOTES); others MuJoCo defaults
    condim: int = 6                                              # 6: sliding, torsional and rolling (3: sliding only)
    solref: tuple[float, float] = (0.005, 1.0)                   # [s, -] (SIM-NOTES)
    solimp: tuple[float, float, float] = (0.95, 0.99, 0.0001)    # [-, -, m] (SIM-NOTES)
    rolling_damping_per_s: float = 4.0    # [1/s] CALIBRATED: viscous rolling resistance of the soft fabric, the
                                          # rate at which a rolling sphere's speed decays on a level sheet; damping
                                          # on the object's rotational dofs (MuJoCo's own rolling friction is
                                          # Coulomb-like, the same at any speed)


@dataclass(frozen=True)
class Solver:
    """Integration: Euler (flex elasticity is refused under the implicit integrators), Newton, 1 kHz as in the paper."""
    timestep_s: float = 0.001             # [s] paper: 1000 Hz
    integrator: str = "Euler"
    solver: str = "Newton"                # CG stalls on the stiff edges (iteration cap) and diverged in some settings
    tolerance: float = 1e-6               # [-] solver stopping tolerance (SIM-NOTES)


@dataclass(frozen=True)
class Camera:
    """Overhead camera looking straight down at the fabric; image right = +x, image up = +y."""
    height_above_z0_m: float = 1.0        # [m] GUESS: not given in the paper
    fovy_deg: float = 45.0                # [deg] vertical field of view: 0.83 m of fabric seen at 1 m
    corner_markers: bool = False          # draw the tracker's four corner markers (host/markers.py) at z0
    object_marker: bool = False           # and its marker on the object's top (not for a rolling sphere:
                                          # the marker would roll away; its colour blob is tracked instead)


@dataclass(frozen=True)
class FallRule:
    """When the object counts as fallen off (any one suffices); see sim/README.md."""
    outside_margin_m: float = 0.05        # [m] marker beyond the frame's edge (|x| > m/2 + margin or |y| > n/2 + margin)
    below_fabric_m: float = 0.02          # [m] object centre below the fabric's lowest vertex by more than this
    floor_z_m: float = 0.1                # [m] object centre below this height above the floor


VISION_MODES = ("aruco", "blob")   # the tracker on rendered frames: ArUco marker, or colour blob


@dataclass(frozen=True)
class Rig:
    """Everything the model is generated from. Change a field with dataclasses.replace or with_object."""
    frame: Frame = field(default_factory=Frame)
    actuators: Actuators = field(default_factory=Actuators)
    fabric: Fabric = field(default_factory=Fabric)
    contact: Contact = field(default_factory=Contact)
    solver: Solver = field(default_factory=Solver)
    camera: Camera = field(default_factory=Camera)
    fall: FallRule = field(default_factory=FallRule)
    object: ObjectSpec = OBJECTS["sphere"]

    def with_object(self, name: str) -> Rig:
        """The same rig carrying another of the paper's objects (a key of objects.OBJECTS)."""
        return dataclasses.replace(self, object=OBJECTS[name])

    def with_vision(self, mode: str) -> Rig:
        """The same rig with the scene markers a tracker mode (VISION_MODES) needs: the corner markers, and for
        aruco the object's marker too."""
        if mode not in VISION_MODES:
            raise ValueError(f"vision mode must be one of {', '.join(VISION_MODES)}, got {mode!r}")
        return dataclasses.replace(self, camera=dataclasses.replace(self.camera, corner_markers=True,
                                                                    object_marker=mode == "aruco"))
