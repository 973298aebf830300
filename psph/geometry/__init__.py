"""Where the particles are: the lattice seeded per slab, polygons and meshes, ground
profiles (inline or CSV) and the particles of polyline boundaries. No MPI, no scene schema."""
