"""The window's panels: digitizing (a FASTRAK feeding a session) and the canopy layout editor."""
