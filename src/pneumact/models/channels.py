"""Signal channels handed to every kernel, in this order (``experiments.pack_channels``).

A model fills the channels it uses and leaves the others empty: the experiment's drive
(pressure, command, set-point, force, velocity or position), the external loads of the
actuator against time and against position, and the valve's normalised area maps
against the command u. A closed loop adds its position set-point, a feed-forward
signal added to the controller output and a force disturbance on a rig's mass; its
plant's drive channel then holds one value, the controller's output, which the loop
writes at ``INPUT_OFFSET`` past the channel's start.
"""

CH_DRIVE = 0
CH_LOAD_T = 1
CH_LOAD_X = 2
CH_MAP_RES = 3
CH_MAP_ATM = 4
N_CHANNELS = 5
CH_SETPOINT = 5
CH_FEEDFORWARD = 6
CH_DISTURBANCE = 7
N_LOOP_CHANNELS = 8
#: [n_terms = 1, kind = PWL, n = 1, t0, value]: where a one-point channel holds its value
INPUT_OFFSET = 4
