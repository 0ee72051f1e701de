"""Elastic-perfectly-plastic Mohr-Coulomb, Abdelrazek et al. (2016) after Bui et al. (2008): MODEL.md section 3,
docs/models/elastoplastic.md."""
