"""The particle state of one rank: the field registry (FIELDS) and the ParticleStore."""
