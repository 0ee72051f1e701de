"""A weakly compressible Newtonian fluid: the toy model that shows what a model package holds
(docs/design.md, "Adding a model"). Not a granular model; tests/test_newtonian.py checks it
against the steady Poiseuille flow between plates."""
