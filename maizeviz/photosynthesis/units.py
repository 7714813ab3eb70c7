"""Units of CO2 assimilation and of PAR.

Leaf physiology speaks of umol CO2 per m2 of leaf per second; crop models (WOFOST) of kg CO2
per ha (of leaf, or of ground) per hour; light of W/m2 (J/m2/s) of PAR or umol of photons.
"""

from __future__ import annotations

#: Molar mass of CO2, g/mol.
CO2_G_PER_MOL = 44.0095
#: 1 umol CO2/m2/s in kg CO2/ha/h: 1e-6 mol x 44.0095 g/mol x 1e-3 kg/g x 1e4 m2/ha x 3600 s/h.
KG_HA_H_PER_UMOL_M2_S = 1e-6 * CO2_G_PER_MOL * 1e-3 * 1e4 * 3600.0
#: Photons per joule of PAR (400-700 nm) in daylight, umol/J (McCree 1972; the light side's
#: ``PAR_UMOL_PER_J_PAR``, repeated here so that the leaf models stand alone).
PAR_UMOL_PER_J = 4.57


def kg_ha_h(umol_m2_s):
    """umol CO2/m2/s -> kg CO2/ha/h (same area basis)."""
    return umol_m2_s * KG_HA_H_PER_UMOL_M2_S


def umol_m2_s(kg_ha_h_):
    """kg CO2/ha/h -> umol CO2/m2/s (same area basis)."""
    return kg_ha_h_ / KG_HA_H_PER_UMOL_M2_S
