"""The one description of the simulated rig: frame, actuators, fabric, contact, solver, camera, fall rule and object.

Every physical quantity of the plant that the paper does not give is declared, with its range and source, in
sim/model/plant.toml, and the defaults here are read from there (the polyester plant). The rig's own constants (frame,
travel, motor) come from protocol/rig.toml (mantaray.protocol.rig); what is left here is the numerics (mesh
resolution, solver) and the renderer's camera.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

from mantaray.protocol import rig as _rig

from .objects import OBJECTS, ObjectSpec
from .parameters import default as _d
from .parameters import lookup


@dataclass(frozen=True)
class Module:
    """The module, or an array of them: modules_x x modules_y modules of size_x x size_y, an actuator on every node of
    their grid (PROTOCOL.md §5; one module: actuators at (±size_x/2, ±size_y/2)), fabric frame origin at the surface's
    centre."""

    size_x_m: float = _rig.default().module_size_x_m  # [m] the paper's m (frame and actuator spacing along x)
    size_y_m: float = _rig.default().module_size_y_m  # [m] the paper's n
    z0_m: float = 1.5  # [m] reference height: corners at a_i = 0 (paper)
    modules_x: int = 1  # modules along x (protocol/rigs/: an array)
    modules_y: int = 1  # modules along y
    build: str = "module"  # the firmware build for this shape (RigDescription.name: mantaray-vmcu-NAME)

    @property
    def grid(self) -> _rig.Grid:
        """The shape: the modules and where each actuator stands."""
        return _rig.Grid(self.modules_x, self.modules_y, self.size_x_m, self.size_y_m)


@dataclass(frozen=True)
class Actuators:
    """Four vertical linear actuators; command a_i [m] lowers corner i (+ = down, PROTOCOL.md §5).

    Modelled as MuJoCo `pid` actuators (position input only) on vertical slide joints, with the
    setpoint rate-limited to the actuator's top speed (`slewmax`): a position servo that reaches a
    new command no faster than the motor can drive the belt.
    """

    range_m: float = _rig.default().actuator_range_m  # [m] travel each way from z0 (protocol/rig.toml)
    motor_speed_rpm: float = _rig.default().motor_speed_rpm  # [rev/min] at full drive (protocol/rig.toml)
    # [m/rev] belt per motor revolution: the plant's, which sets the simulated carriage's top speed (a fitted value;
    # the board's own is protocol/rig.toml's, which the bench-mode firmware never applies: it drives no motor)
    pulley_circumference_m: float = _d("actuators.pulley_circumference_m")
    kp_n_per_m: float = _d("actuators.kp_n_per_m")  # [N/m] servo stiffness; the real loop is on the Uno
    damping_ratio: float = _d("actuators.damping_ratio")  # [-] servo damping as a fraction of critical
    carriage_mass_kg: float = _d("actuators.carriage_mass_kg")  # [kg] gravity-compensated

    @property
    def speed_m_per_s(self) -> float:
        """Top carriage speed [m/s]: motor speed x pulley circumference."""
        return self.motor_speed_rpm / 60.0 * self.pulley_circumference_m


FINER_BY_VERTICES = 6  # [vertices per side] how much finer `finer` is than the fidelity it checks (half the step too)
STATED_AT_RESOLUTION = 15  # [vertices per side] the mesh at which sim/model/plant.toml states the edges' time constant


@dataclass(frozen=True)
class Fidelity:
    """How finely the physics is resolved: fabric vertices per side and the physics step."""

    resolution: int  # [vertices per side] odd
    timestep_s: float  # [s]

    @property
    def label(self) -> str:
        return f"{self.resolution} × {self.resolution}, {self.timestep_s * 1000:g} ms"

    @property
    def slug(self) -> str:
        return f"{self.resolution}x{self.resolution}_{self.timestep_s * 1000:g}ms"

    @property
    def spec(self) -> str:
        """As a command line gives it: RESOLUTION:TIMESTEP."""
        return f"{self.resolution}:{self.timestep_s:g}"

    def finer(self) -> Fidelity:
        """The configuration a fidelity is checked against (`finer` on the command line): FINER_BY_VERTICES more
        vertices a side at half the step, the same integrator and contact."""
        return Fidelity(self.resolution + FINER_BY_VERTICES, self.timestep_s / 2)


# The named fidelities, the one place they are written. The reference is the configuration whose answers the
# project's results hold at, and what every command runs by default: 15 x 15 at 0.5 ms. It is not settled: the
# fidelity gate (sim/evaluation/fidelity.py; docs/results/fidelity/convergence.md) finds 21 x 21 changes its answers, and that
# 0.25 ms keeps them undecided at 200 pairs per controller; it stays the default until a configuration passes, since
# every answer must be re-run there anyway. The fast mode is the one the committed maps, the fitted `paper` plant and
# the tuned settings of docs/results.md were made in, which the gate finds changes the answers: kept by name to read
# them.
FIDELITIES = {"fast": Fidelity(11, 0.002), "reference": Fidelity(15, 0.0005)}
DEFAULT_FIDELITY = FIDELITIES["reference"]


STRETCH_MODELS = lookup("fabric.stretch").choices  # what may hold the sheet's length (Fabric.stretch)
CONTACT_MODELS = lookup("contact.model").choices  # what the object may meet (Contact.model)


@dataclass(frozen=True)
class Fabric:
    """The polyester sheet: a MuJoCo flex grid of point masses (dim 2, full dofs), welded at its four corners to the
    carriages; its length held by its edges or by threads (stretch)."""

    size_m: float = _d("fabric.size_m")  # [m] side of the square sheet (the paper: simulation 0.5, rig 0.6)
    resolution: int = DEFAULT_FIDELITY.resolution  # [vertices per side] odd, so the alternating mesh is
    # mirror-symmetric
    mass_kg: float = _d("fabric.mass_kg")  # [kg] the whole sheet
    young_pa: float = _d("fabric.young_pa")  # [Pa] sets bending stiffness with thickness and Poisson's ratio
    poisson: float = _d("fabric.poisson")  # [-]
    thickness_m: float = _d("fabric.thickness_m")  # [m]
    damping_s: float = _d("fabric.damping_s")  # [s] elastic (Rayleigh, stiffness-proportional) damping
    radius_m: float = _d("fabric.radius_m")  # [m] collision thickness of the triangles
    edge_solref: tuple[float, float] = (_d("fabric.edge_solref[0]"), 1.0)  # [s, -] the edges' length equality or the
    # threads' length limit (stretch): time constant, critical damping
    edge_solimp: tuple[float, float, float] = (
        _d("fabric.edge_solimp[0]"),
        _d("fabric.edge_solimp[1]"),
        _d("fabric.edge_solimp[2]"),
    )  # [-, -, m] edges' impedance d0, dmax, width
    corner_weld_solref: tuple[float, float] = (
        _d("fabric.corner_weld_solref[0]"),
        1.0,
    )  # [s, -] corner-to-carriage welds
    # what holds the sheet's length: "edges" (two-sided) or "threads" (tension only)
    stretch: str = _d("fabric.stretch")
    corner_clamp_m: float = _d("fabric.corner_clamp_m")  # [m] length of each edge, from its corner, the corner's clamp
    # holds straight at the carriage (0: a point attachment)

    def __post_init__(self) -> None:
        if self.resolution < 3 or self.resolution % 2 == 0:
            raise ValueError(f"fabric resolution must be odd and >= 3, got {self.resolution}")
        if self.stretch not in STRETCH_MODELS:
            raise ValueError(f"fabric stretch must be one of {', '.join(STRETCH_MODELS)}, got {self.stretch!r}")

    @property
    def spacing_m(self) -> float:
        """Distance [m] between neighbouring vertices."""
        return self.size_m / (self.resolution - 1)

    @property
    def edge_timeconst_s(self) -> float:
        """[s] The edges' time constant on this mesh: edge_solref[0] is stated at STATED_AT_RESOLUTION and scaled by
        STATED_AT_RESOLUTION / resolution, so the sheet's stretch stiffness is the same physical one on every mesh.

        MuJoCo's constraint stiffness is per unit of the constrained mass: an edge of two vertices of mass m, time
        constant tau and impedance d holds like a spring of d / (1 - d) m / tau^2 [N/m]. A vertex's mass goes as
        1 / N^2, and a square mesh's tension per unit width under a strain is that spring's stiffness times the
        strain whatever the edge length, so tau must go as 1 / N for the sheet to stretch alike on every mesh.
        """
        return self.edge_solref[0] * STATED_AT_RESOLUTION / self.resolution


@dataclass(frozen=True)
class Contact:
    """Object-fabric contact: MuJoCo's, written on both the fabric and the object's geom so its mixing changes nothing,
    or the kernel's (model)."""

    friction: tuple[float, float, float] = (
        _d("contact.friction[0]"),
        _d("contact.friction[1]"),
        _d("contact.friction[2]"),
    )  # sliding [-], torsional [m], rolling [m]
    condim: int = 6  # 6: sliding, torsional and rolling (3: sliding only)
    solref: tuple[float, float] = (_d("contact.solref[0]"), 1.0)  # [s, -] time constant, critical damping
    solimp: tuple[float, float, float] = (
        _d("contact.solimp[0]"),
        _d("contact.solimp[1]"),
        _d("contact.solimp[2]"),
    )  # [-, -, m] d0, dmax, width
    rolling_damping_per_s: float = _d("contact.rolling_damping_per_s")  # [1/s] viscous rolling resistance of the
    # soft fabric, the rate at which a rolling sphere's speed decays on a level
    # sheet; damping on the object's rotational dofs (MuJoCo's own rolling
    # friction is Coulomb-like, the same at any speed)
    model: str = _d("contact.model")  # what the object meets: "mesh" (the flex's triangles) or "kernel"
    # (sim/model/kernel_contact.py: the sheet smoothed over kernel_width_m)
    kernel_width_m: float = _d("contact.kernel_width_m")  # [m] the kernel's support radius
    kernel_stiffness_n_per_m: float = _d("contact.kernel_stiffness_n_per_m")  # [N/m] the kernel contact's spring
    kernel_damping_ratio: float = _d("contact.kernel_damping_ratio")  # [-] its damping, of critical for the
    # reduced mass of the object and the sheet under it

    def __post_init__(self) -> None:
        if self.model not in CONTACT_MODELS:
            raise ValueError(f"contact model must be one of {', '.join(CONTACT_MODELS)}, got {self.model!r}")


@dataclass(frozen=True)
class Solver:
    """Integration: Euler (flex elasticity is refused under the implicit integrators), Newton, at the reference step
    (2 kHz: the paper's 1 kHz is not converged, FIDELITIES)."""

    timestep_s: float = DEFAULT_FIDELITY.timestep_s  # [s]
    integrator: str = "Euler"
    solver: str = "Newton"  # CG stalls on the stiff edges (iteration cap) and diverged in some settings
    tolerance: float = 1e-6  # [-] solver stopping tolerance (SIM-NOTES)

    MAX_TIMESTEP_S = 0.01  # [s] a step no fidelity takes: the sheet's 2 ms constraints already diverge above 1 ms

    def __post_init__(self) -> None:
        if not 0 < self.timestep_s <= self.MAX_TIMESTEP_S:
            raise ValueError(f"timestep must be in (0, {self.MAX_TIMESTEP_S:g}] s, got {self.timestep_s}")


@dataclass(frozen=True)
class Camera:
    """Overhead camera looking straight down at the fabric; image right = +x, image up = +y."""

    height_above_z0_m: float = 1.0  # [m] GUESS: not given in the paper
    fovy_deg: float = 45.0  # [deg] vertical field of view: 0.83 m of fabric seen at 1 m
    corner_markers: bool = False  # draw the tracker's four corner markers (host/markers.py) at z0
    object_marker: bool = False  # and its marker on the object's top (not for a rolling sphere:
    # the marker would roll away; its colour blob is tracked instead)


@dataclass(frozen=True)
class FallRule:
    """When the object counts as fallen off (any one suffices); see sim/README.md."""

    outside_margin_m: float = _d("fall.outside_margin_m")  # [m] centre beyond the frame's edge (|x| > m/2 + margin
    # or |y| > n/2 + margin)
    below_fabric_m: float = _d("fall.below_fabric_m")  # [m] centre below the fabric's lowest vertex by more
    floor_z_m: float = 0.1  # [m] object centre below this height above the floor


VISION_MODES = ("aruco", "blob")  # the tracker on rendered frames: ArUco marker, or colour blob
MIN_STEPS_PER_TIMECONST = 2  # MuJoCo runs a constraint's time constant at no less than two steps (refsafe)


@dataclass(frozen=True)
class Rig:
    """Everything the model is generated from. Change a field with dataclasses.replace or with_object."""

    module: Module = field(default_factory=Module)
    actuators: Actuators = field(default_factory=Actuators)
    fabric: Fabric = field(default_factory=Fabric)
    contact: Contact = field(default_factory=Contact)
    solver: Solver = field(default_factory=Solver)
    camera: Camera = field(default_factory=Camera)
    fall: FallRule = field(default_factory=FallRule)
    object: ObjectSpec = OBJECTS["sphere"]  # object 0: the one a trial controls
    others: tuple[ObjectSpec, ...] = ()  # objects 1, 2, ... on the sheet beside it (with_objects)

    @property
    def objects(self) -> tuple[ObjectSpec, ...]:
        """Every object on the sheet, object 0 first."""
        return (self.object, *self.others)

    def with_description(self, description: _rig.RigDescription) -> Rig:
        """The same plant on the rig a rig file describes (an array: protocol/rigs/): its modules, each with the
        fabric patch, mesh spacing and camera view of one module here, and the firmware built for it (a committed rig
        whose [core] values are the file's; protocol/rig.py firmware_for's RigDescriptionError, a ValueError, where
        none is)."""
        if description.actuator_range_m != self.actuators.range_m:
            raise ValueError(
                f"{description.path.name} gives the actuators +-{description.actuator_range_m:g} m of travel, the "
                f"simulated rig +-{self.actuators.range_m:g} m"
            )
        module = dataclasses.replace(
            self.module,
            size_x_m=description.module_size_x_m,
            size_y_m=description.module_size_y_m,
            modules_x=description.modules_x,
            modules_y=description.modules_y,
            build=_rig.firmware_for(description).name,
        )
        return dataclasses.replace(self, module=module)

    def with_object(self, name: str) -> Rig:
        """The same rig carrying another of the paper's objects (a key of objects.OBJECTS)."""
        return dataclasses.replace(self, object=OBJECTS[name])

    def with_objects(self, names: Sequence[str]) -> Rig:
        """The same rig carrying several of the paper's objects (keys of objects.OBJECTS), object 0 first; how many a
        controller may steer at once is the firmware's to say, not the model's."""
        unknown = [n for n in names if n not in OBJECTS]
        if unknown or not names:
            raise ValueError(
                f"no object {unknown[0]!r}; the objects are: {', '.join(OBJECTS)}" if unknown else "at least one object"
            )
        return dataclasses.replace(self, object=OBJECTS[names[0]], others=tuple(OBJECTS[n] for n in names[1:]))

    def time_constants_s(self) -> dict[str, float]:
        """[s] The constraints' time constants as MuJoCo is given them, by the plant parameter that sets each."""
        return {
            "fabric.edge_solref[0]": self.fabric.edge_timeconst_s,
            "fabric.corner_weld_solref[0]": self.fabric.corner_weld_solref[0],
            "contact.solref[0]": self.contact.solref[0],
        }

    def stiffest(self) -> str:
        """Which parameter makes the stiffest constraint against the step, in words: what to change when the physics
        diverges (the bending stiffness, fabric.young_pa, is the other)."""
        key, tau = min(self.time_constants_s().items(), key=lambda kv: kv[1])
        n, step = self.fabric.resolution, self.solver.timestep_s
        return (
            f"the stiffest constraint is {key} (a time constant of {tau * 1000:.3g} ms at {n} x {n} vertices, "
            f"{tau / step:.3g} steps of {step * 1000:g} ms; MuJoCo runs it at no less than "
            f"{MIN_STEPS_PER_TIMECONST}), then fabric.young_pa's bending: a smaller step, or a softer value of "
            f"either, integrates"
        )

    def with_vision(self, mode: str) -> Rig:
        """The same rig with the scene markers a tracker mode (VISION_MODES) needs: the corner markers, and for
        aruco the object's marker too."""
        if mode not in VISION_MODES:
            raise ValueError(f"vision mode must be one of {', '.join(VISION_MODES)}, got {mode!r}")
        return dataclasses.replace(
            self, camera=dataclasses.replace(self.camera, corner_markers=True, object_marker=mode == "aruco")
        )
