"""Parameters of the compiled kernels.

The kernels take the physical parameters of a joint and its load as one packed float64
vector ``P``; the constants below name its entries. Built from a
:class:`hydroarm.model.joint.ServoJoint` and :class:`~hydroarm.model.joint.Load` by
:func:`hydroarm.model.joint.pack`.
"""

# Indices into the packed parameter vector used by the compiled kernels.
P_AREA = 0
P_FLOW_COEFF = 1
P_E_SAT = 2
P_LEAK = 3
P_VOLUME = 4
P_BETA = 5
P_SUPPLY = 6
P_CRANK = 7
P_RATIO = 8
P_WEIGHT = 9
P_ARM = 10
P_INERTIA = 11
P_HORIZ = 12
P_TORQUE_ARM = 13  # 0: paper's eq. 3 (A p r / n); 1: kinematic (A p r cos(theta/n) / n)
# physics options (docs/physics.md); all off in the paper's model
P_VALVE = 14  # 0: linearised valve with leakage (eq. 1); 1: critically-centred orifice valve
P_P_TRANS = 15  # orifice regularisation pressure [Pa]
P_P_ATM = 16  # return (atmospheric) pressure [Pa], sets the cavitation floor
P_F_COULOMB = 17  # piston Coulomb (sliding) friction [N]
P_F_STATIC = 18  # piston breakaway (stiction) force [N]
P_VISCOUS = 19  # piston viscous friction [N s/m]
P_GB_T0 = 20  # gearbox no-load friction torque at the joint [N m]
P_GB_LOSS = 21  # gearbox loss fraction at full actuator load
P_GB_EXP = 22  # exponent of the gearbox loss law
P_STOP = 23  # end-stop angle |θ₂| [rad] (inf: none)
N_PARAMS = 24

STANDARD_GRAVITY = 9.80665  # g₀ [m/s²] (CGPM 1901): loads given as a mass, the arm's weights
