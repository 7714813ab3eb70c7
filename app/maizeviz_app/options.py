"""Names the menus, the panels and the 3D view share (no Qt, no pyvista: cheap to import)."""

#: Colourings of the canopy: name -> what the View menu says.
COLOURINGS = {"plant": "plant", "leaf": "leaf rank", "light": "light received",
              "assimilation": "CO₂ assimilation"}
#: Camera presets: name -> what the View menu says. Front looks along the rows (+y), side
#: across them (+x), iso from the south-west corner at 45 degrees up; reset goes back to the
#: view the canopy first opened in.
CAMERAS = {"top": "Top", "front": "Front (along the rows)", "side": "Side (across the rows)",
           "iso": "Isometric", "reset": "Reset view"}
#: Earlier names of presets, still understood.
CAMERA_ALIASES = {"along": "front", "across": "side", "perspective": "reset"}
#: Light class of a triangle in the view: value -> (label, colour). The leaf classes are the
#: paper's (maizeviz.light.results.per_leaf.triangle_light): 2 direct, 1 second class, 0 none.
LIGHT_CLASSES = {-2: ("stalk", "#b0875a"), -1: ("not traced", "#c8c8c8"),
                 0: ("no direct light", "#2e5130"), 1: ("second class", "#e39b2d"),
                 2: ("direct", "#fbe54b")}
STALK = -2
NOT_TRACED = -1
#: Tilings of the digitized block offered (tiles along each side; the paper's is 3 x 3). The
#: layout panel's presets are the one place to choose one; the window opens a points file
#: with the tiling of the layout on screen.
TILINGS = (1, 3, 5, 7, 9)


def tiling_of(layout) -> tuple[int, int] | None:
    """Tiles (along x, along y) of a tiled layout; None for a layout file."""
    if layout is None or layout.ground_area is None:
        return None
    tiles = {p.tile for p in layout.placements}
    return len({t[0] for t in tiles}), len({t[1] for t in tiles})
