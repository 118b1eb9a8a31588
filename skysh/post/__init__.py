"""Algorithms on SH coefficients alone: deringing, 8-bit quantization, the normalised basis."""
