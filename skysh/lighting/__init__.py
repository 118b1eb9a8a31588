"""The sun's position, the sun's light from the file, the sun and ground as SH."""
