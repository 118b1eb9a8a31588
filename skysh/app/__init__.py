"""The command line, the viewer and the renders."""
