"""The visual-servoing demos: the player, its clock, run form, panel, 3D nodes and server budget."""
