"""Laws of a round pipe shared by the ``hose`` (lumped segments) and the ``line``
(transmission-line model); not a component (its name starts with ``_``).

    A    = π·d²/4                                     flow area
    1/β_e = 1/β + 1/β_w,   β_w = E·s/d (thin wall)    oil and wall in series (Merritt 1967
                                                      §2.5, the container's compliance)
    c    = √(β_e/ρ),  Z = ρ·c/A                       wave speed, characteristic impedance
    Δp   = 128·μ·ℓ·q/(π·d⁴),  μ = ρ·ν                 laminar (Hagen–Poiseuille)
    Δp   = f·(ℓ/d)·ρ·v·|v|/2,  f = 0.3164·Re^(−1/4)   turbulent, smooth pipe (Blasius, in
                                                      Darcy–Weisbach), Re = |v|·d/ν

(Watton 2009, *Fundamentals of Fluid Power Control*, the chapter on pipelines; Wylie and
Streeter 1993, *Fluid Transients in Systems*, for c and Z.)
"""

from __future__ import annotations

import math

from ..laws import kernel

BLASIUS = 0.3164  # f·Re^(1/4) of a smooth pipe (Blasius 1913), Re ≲ 1e5


@kernel
def pipe_area(diameter):
    """Flow area A [m²] of a round pipe."""
    return 0.25 * math.pi * diameter * diameter


@kernel
def line_bulk_modulus(beta, beta_wall):
    """β_e [Pa] of oil in a pipe whose wall has the bulk modulus β_w (∞: rigid)."""
    return 1.0 / (1.0 / beta + 1.0 / beta_wall)


@kernel
def wave_speed(beta_e, density):
    """Speed of sound c = √(β_e/ρ) [m/s] of the oil column."""
    return math.sqrt(beta_e / density)


@kernel
def laminar_resistance(density, viscosity, length, diameter):
    """Hagen–Poiseuille resistance 128·μ·ℓ/(π·d⁴) [Pa·s/m³], μ = ρ·ν."""
    return 128.0 * density * viscosity * length / (math.pi * diameter**4)


@kernel
def friction_drop(q, density, viscosity, length, diameter, turbulent):
    """Pressure drop [Pa] along a length ℓ of pipe at the flow q (sign of q): laminar, or,
    with ``turbulent``, the larger of the laminar and the Blasius drops (they meet at
    Re ≈ 1190, so the law is continuous; it overstates the friction of the transition
    region 1190 < Re < 2300 by up to 65 %)."""
    lam = laminar_resistance(density, viscosity, length, diameter) * q
    if not turbulent:
        return lam
    v = q / pipe_area(diameter)
    # f·(ℓ/d)·ρ·v|v|/2 with f = 0.3164·(ν/(|v|·d))^(1/4): no singularity at v = 0 or ν = 0
    turb = 0.5 * BLASIUS * density * length * (viscosity / diameter) ** 0.25 / diameter
    turb *= v * abs(v) ** 0.75
    return turb if abs(turb) > abs(lam) else lam
