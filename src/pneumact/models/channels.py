"""Signal channels handed to every kernel, in this order (``experiments.pack_channels``).

A model fills the channels it uses and leaves the others empty: the experiment's drive
(pressure, command, set-point, force, velocity or position), the external loads of the
actuator against time and against position, and the valve's normalised area maps
against the command u.
"""

CH_DRIVE = 0
CH_LOAD_T = 1
CH_LOAD_X = 2
CH_MAP_RES = 3
CH_MAP_ATM = 4
N_CHANNELS = 5
