"""The rig as MuJoCo sees it: its geometry and fidelities, the plant's values, the objects, the generated scene."""
