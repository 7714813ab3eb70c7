"""What the 3D view shows of the study, without Qt or VTK: the colouring and the camera preset
asked for (napari keeps its ``Camera`` and each layer's colormap in the model the same way);
the colour scales are :mod:`maizeviz_app.colour`'s. The viewport only renders this state
(:mod:`maizeviz_app.view_link` wires them); a script sets it as the View menu does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from psygnal import SignalGroup, evented

from maizeviz_app.options import CAMERA_ALIASES, CAMERAS, COLOURINGS

#: How the plants other than the selection are drawn, and what the View menu calls it.
OTHERS = {"shown": "Others shown", "faded": "Others faded (the selection seen through them)",
          "hidden": "Others hidden (the selection alone)"}
#: The opacity of the faded others.
FADED_OPACITY = 0.15

#: A camera's position, focal point and view up (cm).
Pose = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]


@evented
@dataclass
class ViewState:
    """The 3D view's state (evented: ``view.events.colouring`` emits ``(new, old)``).

    Attributes
    ----------
    colouring : a key of :data:`maizeviz_app.options.COLOURINGS`: ``plant``, ``leaf``,
        ``light`` (the light last computed on the canopy shown) or ``assimilation`` (its CO2
        assimilation, with a leaf model)
    camera : the camera preset last asked for, a key of :data:`maizeviz_app.options.CAMERAS`
        (asking for it again frames the canopy again: :meth:`ask_camera`)
    others : how the plants other than the selected one are drawn while one is selected:
        ``shown`` (as they are), ``faded`` (nearly transparent: the selection seen through
        them) or ``hidden`` (the selection alone); a key of :data:`OTHERS`
    pose : ((3,), (3,), (3,)) float, cm, or None
        Where the camera is: its position, the point it looks at and its up direction, as
        the view last reported it (after a preset, a drag or a wheel turn); set by a script,
        the view goes there. None until a view has shown a canopy.
    """

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    colouring: str = "leaf"
    camera: str = "reset"
    pose: Pose | None = None
    others: str = "shown"

    def ask_camera(self, name: str) -> None:
        """Point the camera by preset ``name`` (earlier names understood), even when it is
        the preset already asked for; ValueError for a name that is none."""
        name = CAMERA_ALIASES.get(name, name)
        if name not in CAMERAS:
            raise ValueError(f"unknown camera preset {name}; one of {', '.join(CAMERAS)}")
        if name == self.camera:
            self.events.camera.emit(name, name)
        else:
            self.camera = name

    @staticmethod
    def check_colouring(what: str) -> None:
        if what not in COLOURINGS:
            raise ValueError(f"unknown colouring {what}; one of {', '.join(COLOURINGS)}")
