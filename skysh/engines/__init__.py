"""Engines' SH dialects (three.js, Filament, Unity, Babylon.js, Unreal) and the sun as their lights."""
