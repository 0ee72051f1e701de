"""The steady uniform flow of a mu(I) layer down an inclined plane, [M56]: what the model
predicts, in numpy (the inclined-plane validation and the Mach advice read it). ``material``:
a MuIMaterial (parameters.py)."""
from __future__ import annotations

import math

import numpy as np


def steady_inertial_number(material, slope_rad: float) -> float:
    """I_u of [M56]; only slopes between arctan(mu_s) and arctan(mu_2) flow steadily."""
    tan = math.tan(slope_rad)
    if not material.mu_s < tan < material.mu_2:
        raise ValueError(f"slope {math.degrees(slope_rad):.2f} deg is outside the steady range "
                         f"({material.static_friction_deg}, {material.limit_friction_deg}) deg")
    return material.reference_inertial_number * (tan - material.mu_s) / (material.mu_2 - tan)


def steady_solid_fraction(material, slope_rad: float) -> float:
    I_u = steady_inertial_number(material, slope_rad)
    return material.solid_fraction_max - (material.solid_fraction_max - material.solid_fraction_min) * I_u


def analytic_velocity(z, height: float, material, slope_rad: float, g: float) -> np.ndarray:
    """[M56]: down-slope velocity at height z above the bed  [m/s]."""
    z = np.clip(np.asarray(z, float), 0.0, height)
    I_u = steady_inertial_number(material, slope_rad)
    phi_u = steady_solid_fraction(material, slope_rad)
    scale = 2.0 * I_u / (3.0 * material.grain_diameter) * math.sqrt(phi_u * g * math.cos(slope_rad))
    return scale * (height**1.5 - (height - z) ** 1.5)


def analytic_pressure(z, height: float, material, slope_rad: float, g: float) -> np.ndarray:
    """Hydrostatic pressure phi_u rho_s g cos(theta) (H - z)  [Pa]."""
    z = np.clip(np.asarray(z, float), 0.0, height)
    phi_u = steady_solid_fraction(material, slope_rad)
    return phi_u * material.grain_density * g * math.cos(slope_rad) * (height - z)


def steady_height(mass_per_length: float, material, slope_rad: float, g: float) -> float:
    """Height of the steady layer holding ``mass_per_length`` [kg/m (2D)]  [m]."""
    phi_u = steady_solid_fraction(material, slope_rad)
    height = mass_per_length / (phi_u * material.grain_density)
    for _ in range(20):  # grain compression under the mean pressure (tiny, ~K_t p)
        p_mean = 0.5 * phi_u * material.grain_density * g * math.cos(slope_rad) * height
        height = mass_per_length / (phi_u * material.grain_density * (1.0 + material.grain_compressibility * p_mean))
    return height
