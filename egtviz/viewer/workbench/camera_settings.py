"""One camera's settings folder in the workbench: its pose, its model's choices and parameters, its Remove button.

Every field is judged on the server in the field's own units (:mod:`egtviz.viewer.workbench.fields`, ranges from
:mod:`egtviz.scene.limits` and the model's parameter specs); a lesson's narrower ranges are asked of the tab's
:class:`~egtviz.viewer.workbench.lesson_policy.LessonPolicy` before a value is committed.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from functools import lru_cache
from typing import TYPE_CHECKING, TypeAlias

from ...scene import CameraSpec, SceneError, limits
from ...scene.cameras import camera_entry, model_choices
from ...scene.specs import OutOfRangeError
from .camera_fields import CameraField, camera_fields, field_rules as _field_rules
from .fields import FieldError, NumberRule, format_number, format_numbers, parse_numbers
from .models import SHORT_LABELS
from .gui_text import plain, set_value

if TYPE_CHECKING:
    import viser

    from .tab_context import TabContext

    #: A camera folder's field: a text field (the pose, a model parameter), a model choice or a slider.
    FieldHandle: TypeAlias = viser.GuiTextHandle | viser.GuiDropdownHandle[str] | viser.GuiSliderHandle[float]

__all__ = ["FIELD_RULES", "CameraSettings", "field_rules", "spec_values"]


def _rules(label: str, unit: str, rng: limits.Range, *, scale: float = 1.0,
           axes: Sequence[str] = ("",)) -> tuple[NumberRule, ...]:
    """One field rule per axis from a :mod:`egtviz.scene.limits` range, converted to the field's unit by ``scale``."""
    return tuple(NumberRule(f"{label} {a}".strip(), unit, rng.low * scale, rng.high * scale, integer=rng.integer)
                 for a in axes)


#: What each camera field accepts, in the units the field shows (the scene's limits, converted).
FIELD_RULES: dict[str, tuple[NumberRule, ...]] = {
    "position": _rules("position", "m", limits.COORDINATE, axes="xyz"),
    "ypr": _rules("angle", "deg", limits.ANGLE_DEG, axes=("yaw", "pitch", "roll")),
}
"""The pose fields every camera has; a model's own fields take their rules from its parameters
(:mod:`egtviz.viewer.workbench.camera_fields`)."""

def _restated(exc: OutOfRangeError, name: str, model_kind: str) -> FieldError:
    """The model's range refusal restated for the user: the camera, the field's words and units (as the model's
    entry words them)."""
    terms = camera_entry(model_kind).terms
    label, unit, scale = terms.get(exc.field, (exc.field.replace("_", " "), exc.limit.unit, 1.0))
    rule = NumberRule(label, unit, exc.limit.low * scale, exc.limit.high * scale, integer=exc.limit.integer)
    try:
        rule.check(float(exc.value) * scale, owner=name)
    except FieldError as restated:
        return restated
    except (TypeError, ValueError):  # a value that is no number: keep the model's own words
        pass
    return FieldError(f"{name}: {exc}")


@lru_cache(maxsize=16)
def _model_fields(model_kind: str) -> dict[str, CameraField]:
    """A model's GUI fields by key (from its entry)."""
    return {f.key: f for f in camera_fields(model_kind)}


def spec_values(spec: CameraSpec) -> dict[str, tuple[float, ...]]:
    """A camera spec's values as its fields show them (model parameters -> the fields' units)."""
    values: dict[str, tuple[float, ...]] = {"position": tuple(spec.position), "ypr": tuple(spec.ypr_deg)}
    params = spec.model_values()
    for key, field in _model_fields(spec.model_kind).items():
        values[key] = field.shown(params)
    return values


def field_rules(spec: CameraSpec, key: str) -> tuple[NumberRule, ...]:
    """What field ``key`` of this camera accepts (its parameters' ranges in the field's units)."""
    if key in FIELD_RULES:
        return FIELD_RULES[key]
    fields = _model_fields(spec.model_kind)
    if key not in fields:
        raise FieldError(f"{spec.name}: no field {key!r} on a {spec.model.label.lower()}")
    return _field_rules(fields[key], spec.model_kind)


def _spec_fields(spec: CameraSpec, key: str, v: tuple[float, ...]) -> dict[str, object]:
    """Parsed field values as spec fields (the fields' units -> model parameters -> spec fields)."""
    if key == "position":
        return {"position": v}
    if key == "ypr":
        return {"ypr_deg": v}
    field = _model_fields(spec.model_kind).get(key)
    if field is None:
        raise FieldError(f"unknown field {key!r}")
    return spec.fields_for_parameters(**field.parameters_of(v))


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
        fields = _model_fields(spec.model_kind)
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
                    (p,) = _field_rules(field, spec.model_kind)
                    if p.lo is None or p.hi is None:  # viser compares a slider's bounds: neither may be open
                        raise TypeError(f"{spec.name}: the slider {field.title!r} needs both bounds")
                    f[key] = sliders[key] = gui.add_slider(field.title, min=p.lo, max=p.hi, step=0.01,
                                                           initial_value=values[key][0], hint=field.hint or None)
                else:
                    f[key] = texts[key] = gui.add_text(field.title, format_numbers(values[key]),
                                                       hint=field.hint or None)
            remove = gui.add_button(f"Remove {spec.name}", color="red")
        tab, name = self.tab, self.name
        tab.on(remove.on_click, lambda _: tab.user_event(lambda: tab.model.remove_camera(name)))
        return f

    def _attach(self) -> None:
        tab = self.tab
        for key in self.fields:
            if key in self._choices:
                def chosen(e: viser.GuiEvent[viser.GuiDropdownHandle[str]], k: str = key) -> None:
                    tab.user_event(lambda: self.set_choice(k, e.target.value))

                tab.on(self._choices[key].on_update, chosen)
            elif key in self._sliders:
                # A slider acts at once (the image morphs as it moves); one slide is one undo step.
                def slid(e: viser.GuiEvent[viser.GuiSliderHandle[float]], k: str = key) -> None:
                    tab.user_event(lambda: self.apply_slider(k, e.target.value))

                tab.on(self._sliders[key].on_update, slid)
            else:
                def typed(e: viser.GuiEvent[viser.GuiTextHandle], k: str = key) -> None:
                    tab.text_event((self.name, k), lambda text: self.apply_field(k, text), e.target.value)

                tab.on(self._texts[key].on_update, typed)

    def _spec(self) -> CameraSpec | None:
        """The camera's current spec, or None once it was removed (the user may still be typing)."""
        scene = self.tab.model.scene
        return scene.camera(self.name) if self.name in scene.camera_names else None

    def apply_field(self, key: str, text: object) -> None:
        """Judge a text field's text and commit it (a number left as shown keeps the model's full precision)."""
        spec = self._spec()
        if spec is None:
            return
        values = parse_numbers(text, field_rules(spec, key), owner=self.name)
        current = spec_values(spec).get(key)
        if current is None:
            raise FieldError(f"{self.name}: no field {key!r} on a {spec.model.label.lower()}")
        values = tuple(c if format_number(v) == format_number(c) else v for v, c in zip(values, current))
        if values == current:
            return  # nothing edited (e.g. our own write-back, or the same text again)
        self._update(spec, _spec_fields(spec, key, values))

    def apply_slider(self, key: str, value: object) -> None:
        """Commit a slider's value (one slide merges into one undo step)."""
        spec = self._spec()
        if spec is None:
            return
        (rule,) = field_rules(spec, key)
        if isinstance(value, bool) or not isinstance(value, (int, float)):  # a raw client can send anything
            raise FieldError(f"{self.name}: {rule.label} must be a number, got {plain(repr(value), 40)}")
        x = (rule.check(float(value), owner=self.name),)
        if x == spec_values(spec).get(key):
            return
        self._update(spec, _spec_fields(spec, key, x), merge_key=("slider", self.name, key))

    def _update(self, spec: CameraSpec, fields: dict[str, object], merge_key: Hashable = None) -> None:
        name = spec.name
        if all(getattr(spec, k) == v for k, v in fields.items()):
            return
        refusal = self.tab.policy().refusal(name, fields)
        if refusal is not None:
            raise FieldError(refusal)
        try:
            self.tab.model.update_camera(name, merge_key=merge_key, **fields)
        except OutOfRangeError as exc:  # a limit across fields (e.g. focal length in pixels): say it in UI terms
            raise _restated(exc, name, spec.model_kind) from exc
        except SceneError as exc:
            if str(exc).startswith(f"{name}:"):
                raise
            raise SceneError(f"{name}: {exc}") from exc

    def set_choice(self, key: str, value: object) -> None:
        """Switch the camera among the models its spec builds (a mirror's shape); the spec adapts its parameters."""
        spec = self._spec()
        if spec is None:
            return
        options = model_choices(type(spec)).get(key, ())
        if value not in options:  # a raw client can send any string
            raise FieldError(f"{self.name}: {key} must be one of {', '.join(options)}, got {plain(repr(value), 40)}")
        if getattr(spec, key) != value:
            self.tab.model.update_camera(self.name, **{key: value})

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
