"""The coefficient file: its container, the sky and sun tables, the offline fits."""
