"""The rig's constants for the host and the simulation. Generated from protocol/rig.toml by protocol/generate.py; do not edit."""

ACTUATOR_COUNT = 4  # Linear actuators, one at each corner (PROTOCOL.md §5). (identify_reply.actuator_count)
ACTUATOR_RANGE_M = 0.25  # [m] Travel of each actuator about its reference height z0: commands live in [-range, +range] (the paper). (identify_reply.actuator_range)
MODULE_SIZE_X_M = 0.5  # [m] The module's size m along x: actuators at x = +-m/2 (the paper); configure's default.
MODULE_SIZE_Y_M = 0.5  # [m] The module's size n along y: actuators at y = +-n/2 (the paper); configure's default.
ENCODER_COUNTS = 4096  # Counts per revolution of the 12-bit magnetic encoder (AS5600). (identify_reply.encoder_counts)
PULLEY_CIRCUMFERENCE_M = 0.04  # [m/rev] Belt travel per motor revolution: a GT2 20-tooth pulley. Measure yours (docs/BRINGUP.md). (identify_reply.pulley_circumference)
MOTOR_SPEED_RPM = 120.0  # [rev/min] Motor shaft speed at full drive: RS Pro 834-7590, 12 V, no load (the paper).
ACTUATOR_PERIOD_US = 4000  # [us] Period of the four actuator position loops (250 Hz). (identify_reply.actuator_period)

# What the firmware reports at identify (identify_reply field -> this description's value).
REPORTED = {'actuator_count': ACTUATOR_COUNT, 'actuator_range': ACTUATOR_RANGE_M, 'encoder_counts': ENCODER_COUNTS, 'pulley_circumference': PULLEY_CIRCUMFERENCE_M, 'actuator_period': ACTUATOR_PERIOD_US}
REPORTED_UNITS = {'actuator_count': '', 'actuator_range': 'm', 'encoder_counts': '', 'pulley_circumference': 'm/rev', 'actuator_period': 'us'}
