"""One camera's settings folder in the workbench: its pose, its model's choices and parameters, its Remove button.

The folder only maps its widgets to the tab controller's intents (:class:`~egtviz.controllers.workbench.
WorkbenchController`: ``set_field``, ``slide``, ``choose_model``, ``remove_camera``), which judge every value in the
field's own units (:mod:`egtviz.controllers.workbench_cameras`), and writes the camera's values back.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeAlias

from ...controllers.workbench_cameras import model_field_rules, model_fields, spec_values
from ...controllers.workbench_fields import format_numbers
from ...scene import CameraSpec
from ...scene.cameras import model_choices
from .models import SHORT_LABELS
from .gui_text import set_value

if TYPE_CHECKING:
    import viser

    from .tab_context import TabContext

    #: A camera folder's field: a text field (the pose, a model parameter), a model choice or a slider.
    FieldHandle: TypeAlias = viser.GuiTextHandle | viser.GuiDropdownHandle[str] | viser.GuiSliderHandle[float]

__all__ = ["CameraSettings"]


class CameraSettings:
    """One camera's folder: its fields by key (:attr:`fields`), what they do, and their write-back.

    Args:
        tab: the tab's services (its GUI, model, event wrappers and lesson policy are used).
        spec: the camera's spec when the folder is built (its name and model kind stay for the folder's life).
        parent: the folder the camera's folder goes in.
        expand: whether the folder starts open.
    """

    def __init__(self, tab: TabContext, spec: CameraSpec, parent: viser.GuiFolderHandle, *, expand: bool) -> None:
        self.tab = tab
        self.name = spec.name
        gui = tab.client.gui
        with parent:
            self.folder = gui.add_folder(f"{spec.name} ({SHORT_LABELS[spec.model_kind]})", expand_by_default=expand)
        # The same fields by kind, typed for their write-back: text fields, model choices, sliders.
        self._texts: dict[str, viser.GuiTextHandle] = {}
        self._choices: dict[str, viser.GuiDropdownHandle[str]] = {}
        self._sliders: dict[str, viser.GuiSliderHandle[float]] = {}
        #: The folder's GUI fields by key (``position``, ``ypr``, a model choice, a model parameter).
        self.fields = self._build(spec)
        self._synced: CameraSpec | None = None
        self._attach()

    def _build(self, spec: CameraSpec) -> dict[str, FieldHandle]:
        """The pose fields, the model choices and one field per model parameter (or pair), units in the labels."""
        gui = self.tab.client.gui
        values = spec_values(spec)
        fields = model_fields(spec.model_kind)
        f: dict[str, FieldHandle] = {}
        texts, choices, sliders = self._texts, self._choices, self._sliders
        with self.folder:
            f["position"] = texts["position"] = gui.add_text(
                "position x, y, z (m)", format_numbers(values["position"]),
                hint="Camera centre (single viewpoint) in world coordinates: x, y, z.")
            hint = spec.ANGLE_CONVENTION
            f["ypr"] = texts["ypr"] = gui.add_text("yaw, pitch, roll (deg)", format_numbers(values["ypr"]), hint=hint)
            gui.add_markdown(f"<small>{hint}</small>")
            for key, options in model_choices(type(spec)).items():
                f[key] = choices[key] = gui.add_dropdown(key, options, initial_value=getattr(spec, key))
            for key, field in fields.items():
                if field.slider:
                    (p,) = model_field_rules(field, spec.model_kind)
                    if p.lo is None or p.hi is None:  # viser compares a slider's bounds: neither may be open
                        raise TypeError(f"{spec.name}: the slider {field.title!r} needs both bounds")
                    f[key] = sliders[key] = gui.add_slider(field.title, min=p.lo, max=p.hi, step=0.01,
                                                           initial_value=values[key][0], hint=field.hint or None)
                else:
                    f[key] = texts[key] = gui.add_text(field.title, format_numbers(values[key]),
                                                       hint=field.hint or None)
            remove = gui.add_button(f"Remove {spec.name}", color="red")
        tab, name = self.tab, self.name
        tab.on(remove.on_click, lambda _: tab.user_event(lambda: tab.controller.remove_camera(name)))
        return f

    def _attach(self) -> None:
        tab = self.tab
        for key in self.fields:
            if key in self._choices:
                def chosen(e: viser.GuiEvent[viser.GuiDropdownHandle[str]], k: str = key) -> None:
                    tab.user_event(lambda: tab.controller.choose_model(self.name, k, e.target.value))

                tab.on(self._choices[key].on_update, chosen)
            elif key in self._sliders:
                # A slider acts at once (the image morphs as it moves); one slide is one undo step.
                def slid(e: viser.GuiEvent[viser.GuiSliderHandle[float]], k: str = key) -> None:
                    tab.user_event(lambda: tab.controller.slide(self.name, k, e.target.value))

                tab.on(self._sliders[key].on_update, slid)
            else:
                def typed(e: viser.GuiEvent[viser.GuiTextHandle], k: str = key) -> None:
                    tab.text_event((self.name, k), lambda text: tab.controller.set_field(self.name, k, text),
                                   e.target.value)

                tab.on(self._texts[key].on_update, typed)

    def sync(self, spec: CameraSpec, *, force: bool) -> None:
        """Write ``spec``'s values into the fields (``force=False``: skipped when ``spec`` is the one last written)."""
        if not force and self._synced is spec:
            return
        self._synced = spec
        for key, values in spec_values(spec).items():
            if key in self._sliders:
                set_value(self._sliders[key], values[0])
            else:
                set_value(self._texts[key], format_numbers(values))
        for key in model_choices(type(spec)):
            set_value(self._choices[key], getattr(spec, key))

    def remove(self) -> None:
        """Take the folder off the page."""
        self.folder.remove()
