"""Self-contained C, GLSL, HLSL, JavaScript and JSON that reproduce the runtime."""
