"""Indices shared by the compiled kernels: parameter slots and signal channels.

Kernels read parameters only through these names, never through literal numbers.
"""

from ..parameters.spec import I_DERIVED, I_POLYTROPIC, INDEX

I_M = INDEX["m"]
I_F0 = INDEX["F0"]
I_K = INDEX["k"]
I_XMAX = INDEX["x_max"]
I_KSTOP = INDEX["k_stop"]
I_CSTOP = INDEX["c_stop"]
I_SIGMA0 = INDEX["sigma0"]
I_SIGMA1 = INDEX["sigma1"]
I_SIGMA2 = INDEX["sigma2"]
I_FC = INDEX["Fc"]
I_FS = INDEX["Fs"]
I_VS = INDEX["vs"]
I_DELTA = INDEX["delta"]
I_VREG = INDEX["v_reg"]
I_DAHL_ALPHA = INDEX["dahl_alpha"]
I_BW_BETA = INDEX["bw_beta"]
I_BW_GAMMA = INDEX["bw_gamma"]
I_BW_N = INDEX["bw_n"]
I_AD = INDEX["A_d"]
I_V0 = INDEX["V0"]
I_PATM = INDEX["p_atm"]
I_PRES = INDEX["p_res"]
I_GAMMA = INDEX["gamma"]
I_R = INDEX["R"]
I_T = INDEX["T"]
I_RLIN = INDEX["r_lin"]
I_ARES = INDEX["A_res"]
I_AATM = INDEX["A_atm"]
I_REG_KP = INDEX["reg_kp"]
I_REG_TI = INDEX["reg_ti"]
I_REG_TAU = INDEX["reg_tau"]
I_KDRIVE = INDEX["k_drive"]
I_VDRIVE = INDEX["v_drive"]
I_NPOLY = I_POLYTROPIC
# derived orifice-flow constants (see pneumatics.derive_flow_constants)
I_FLOW_RCRIT = I_DERIVED  # critical pressure ratio r_c
I_FLOW_PHICHOKED = I_DERIVED + 1  # Φ in choked flow
I_FLOW_COEF = I_DERIVED + 2  # sqrt(γ/(R·T))
I_FLOW_LINSLOPE = I_DERIVED + 3  # Φ(r_lin)/(1 − r_lin): slope of the laminar branch

# Signal channels handed to every kernel.
CH_DRIVE = 0  # pressure, command, set-point, force, velocity or position, by model
CH_LOAD_T = 1  # external load F_ext(t) [N]
CH_LOAD_X = 2  # external load map F_ext(x) [N], evaluated at the position
CH_MAP_RES = 3  # valve: normalised area chamber -> reservoir against command u
CH_MAP_ATM = 4  # valve: normalised area atmosphere -> chamber against command u
N_CHANNELS = 5
