"""Names the menus, the panels and the 3D view share (no Qt, no pyvista: cheap to import)."""

#: Colourings of the canopy: name -> what the View menu says.
COLOURINGS = {"plant": "plant", "leaf": "leaf rank", "light": "light received"}
#: Camera presets: name -> what the View menu says.
CAMERAS = {"top": "Top", "along": "Along the rows", "across": "Across the rows",
           "perspective": "Perspective"}
#: Light class of a triangle in the view: value -> (label, colour). The leaf classes are the
#: paper's (maizeviz.light.leaf_light.triangle_light): 2 direct, 1 second class, 0 none.
LIGHT_CLASSES = {-2: ("stalk", "#b0875a"), -1: ("not traced", "#c8c8c8"),
                 0: ("no direct light", "#2e5130"), 1: ("second class", "#e39b2d"),
                 2: ("direct", "#fbe54b")}
STALK = -2
NOT_TRACED = -1
