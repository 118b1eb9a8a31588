"""Real spherical harmonics: layout, basis, projection, rotation, the exact minimum."""
