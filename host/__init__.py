"""Host-side tools for the rig and the virtual MCU."""
