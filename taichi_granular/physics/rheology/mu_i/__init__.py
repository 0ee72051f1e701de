"""mu(I) rheology with compressible grains, Minatti & Paris (2015): MODEL.md section 1, docs/models/mu_i.md."""
