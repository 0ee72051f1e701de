"""Unified hypoplastic + Bagnold model of Peng et al. (2016): MODEL.md section 2, docs/models/hypoplastic.md."""
