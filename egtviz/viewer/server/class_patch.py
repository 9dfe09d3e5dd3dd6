"""One class shared by several worker processes: the changes each makes, as small JSON patches.

Each worker keeps its own :class:`~egtviz.classroom.Classroom`; what changed in it since the worker last spoke is
a *patch* (:func:`diff`), which the hub in the supervising process merges into its copy of the class and relays
to the other workers, which merge it into theirs (:func:`merge_into`). Merging goes field by field (and student
by student, answer by answer), so two workers that change different things at once lose neither change.

A patch is plain JSON data::

    {"set": {field: value},                          # mode, pause, the shared scene, ... whole
     "keys": {field: {"set": {key: value}, "del": [key]}},   # students, their scenes, labels, pacing
     "answers": {question: {student: answer}},
     "tabs": {"set": {tab: [name, following, lesson, step]}, "del": [tab]}}

A worker's own tabs carry its viser client ids; the hub gives the other workers' tabs ids of their own
(:func:`global_tab`) so that ids of different workers never meet.
"""

from __future__ import annotations

import copy
import dataclasses
import json
from typing import Any

from ...classroom import ClassState, Mode
from ...classroom.answers import AnswerBook
from ...classroom.state import TabState

__all__ = ["KEYED", "SCALARS", "TAB_SPAN", "JsonObject", "apply_patch", "diff", "empty_patch", "full_patch",
           "global_tab", "is_empty", "merge_into", "normal", "parsed_patch"]

#: A JSON object as the bus carries it: a class state in :func:`normal` form, a patch, a message. Its values are
#: what ``json`` makes, read by key and checked where they are used (a class state by :func:`parsed_patch`).
JsonObject = dict[str, Any]

#: Fields replaced whole.
SCALARS = ("shared", "mode", "cameras_locked", "pause", "allowed", "snapshots_taken", "names_shown", "question",
           "shown")
#: Fields merged key by key (``students``: the keys only).
KEYED = ("students", "scenes", "labels", "paced")
#: A worker's own tab ids are below this; worker ``i``'s tabs are ``(i + 1) * TAB_SPAN + id`` elsewhere.
TAB_SPAN = 1 << 40


def global_tab(worker: int, tab: int) -> int:
    """The id another worker knows tab ``tab`` of worker ``worker`` by."""
    return (worker + 1) * TAB_SPAN + tab


def normal(state_json: str | dict) -> JsonObject:
    """A class state (:meth:`~egtviz.classroom.Classroom.to_json`) in the form patches address: students and
    tabs as dicts (tab ids as text, as JSON keeps them)."""
    d = json.loads(state_json) if isinstance(state_json, str) else state_json
    out = {f: d[f] for f in SCALARS}
    out["students"] = {name: None for name in d["students"]}
    for f in ("scenes", "labels", "paced"):
        out[f] = dict(d[f])
    out["answers"] = {q: {"version": e["version"], "answers": dict(e["answers"])} for q, e in d["answers"].items()}
    out["tabs"] = {str(tab): [name, following, lesson, step] for tab, name, following, lesson, step in d["tabs"]}
    return out


def empty_patch() -> JsonObject:
    return {"set": {}, "keys": {}, "answers": {}, "tabs": {"set": {}, "del": []}}


def is_empty(patch: JsonObject) -> bool:
    tabs = patch.get("tabs", {})
    return not (patch.get("set") or patch.get("keys") or patch.get("answers") or tabs.get("set") or tabs.get("del"))


def diff(last: JsonObject, cur: JsonObject, *, own_tabs: bool = True) -> JsonObject:
    """What changed from ``last`` to ``cur`` (both :func:`normal`); ``own_tabs``: only tabs below
    :data:`TAB_SPAN` (a worker speaks for its own tabs only)."""
    patch = empty_patch()
    patch["set"] = {f: cur[f] for f in SCALARS if f not in last or last[f] != cur[f]}
    for f in KEYED:
        a, b = last.get(f, {}), cur[f]
        changed = {k: v for k, v in b.items() if k not in a or a[k] != v}
        gone = [k for k in a if k not in b]
        if changed or gone:
            patch["keys"][f] = {"set": changed, "del": gone}
    old_answers = last.get("answers", {})
    for q, e in cur["answers"].items():
        before = old_answers.get(q, {}).get("answers", {})
        changed = {s: v for s, v in e["answers"].items() if s not in before or before[s] != v}
        if changed:
            patch["answers"][q] = changed

    def mine(tab: str) -> bool:
        return not own_tabs or int(tab) < TAB_SPAN

    a, b = last.get("tabs", {}), cur["tabs"]
    patch["tabs"]["set"] = {t: v for t, v in b.items() if mine(t) and a.get(t) != v}
    patch["tabs"]["del"] = [t for t in a if mine(t) and t not in b]
    return patch


def full_patch(state: JsonObject, tabs: dict[str, list]) -> JsonObject:
    """A patch that brings an empty class to ``state`` (:func:`normal`), with ``tabs`` as its tabs."""
    patch = empty_patch()
    patch["set"] = {f: state[f] for f in SCALARS}
    patch["keys"] = {f: {"set": dict(state[f]), "del": []} for f in KEYED if state[f]}
    patch["answers"] = {q: dict(e["answers"]) for q, e in state["answers"].items()}
    patch["tabs"]["set"] = dict(tabs)
    return patch


def apply_patch(state: JsonObject, patch: JsonObject) -> JsonObject:
    """``state`` (:func:`normal`) with ``patch`` merged in, as a new dict (``state`` is left as it was)."""
    out = dict(state)
    out.update(patch.get("set", {}))
    for f, change in patch.get("keys", {}).items():
        if f in KEYED:
            merged = dict(out.get(f, {}))
            merged.update(change.get("set", {}))
            for k in change.get("del", []):
                merged.pop(k, None)
            out[f] = merged
    if patch.get("answers"):
        answers = copy.deepcopy(out.get("answers", {}))
        for q, changed in patch["answers"].items():
            e = answers.setdefault(q, {"version": 0, "answers": {}})
            e["answers"].update(changed)
            e["version"] += 1
        out["answers"] = answers
    tabs = patch.get("tabs", {})
    if tabs.get("set") or tabs.get("del"):
        merged = dict(out.get("tabs", {}))
        merged.update(tabs.get("set", {}))
        for t in tabs.get("del", []):
            merged.pop(t, None)
        out["tabs"] = merged
    if "mode" in patch.get("set", {}):
        following = patch["set"]["mode"] == Mode.FOLLOW.value
        out["tabs"] = {t: v if v[0] is None else [v[0], following, *v[2:]] for t, v in out.get("tabs", {}).items()}
    return out


def parsed_patch(patch: JsonObject) -> ClassState:
    """The values ``patch`` sets, read and checked as a class state would be (done before taking the class's
    lock: scenes are parsed here).

    Raises:
        ClassroomError: a value the class would refuse.
    """
    template = ClassState().to_dict()
    template.update(patch.get("set", {}))
    keys = patch.get("keys", {})
    template["students"] = list(keys.get("students", {}).get("set", {}))
    for f in ("scenes", "labels", "paced"):
        template[f] = keys.get(f, {}).get("set", {})
    template["tabs"] = [[int(t), *v] for t, v in patch.get("tabs", {}).get("set", {}).items()]
    return ClassState.from_dict(template)


def merge_into(old: ClassState, patch: JsonObject, parsed: ClassState) -> ClassState:
    """A new class state: ``old`` with ``patch`` (read as ``parsed``, :func:`parsed_patch`) merged in.

    ``old`` is not changed. A new mode sets every student tab's follow, as the instructor's
    :meth:`~egtviz.classroom.Classroom.set_mode` does in the worker it ran in.
    """
    sets = patch.get("set", {})
    new = dataclasses.replace(old, **{f: getattr(parsed, f) for f in SCALARS if f in sets})
    for f, change in patch.get("keys", {}).items():
        if f not in KEYED:
            continue
        merged = dict(getattr(old, f))
        merged.update(getattr(parsed, f))
        for k in change.get("del", []):
            merged.pop(k, None)
        setattr(new, f, merged)
    if patch.get("answers"):
        book = old.answers.to_dict()
        for q, changed in patch["answers"].items():
            e = book.setdefault(q, {"version": 0, "answers": {}})
            e["answers"].update(changed)
            e["version"] += 1
        new.answers = AnswerBook.from_dict(book)
    tabs = dict(old.tabs)
    for t in patch.get("tabs", {}).get("del", []):
        tabs.pop(int(t), None)
    tabs.update(parsed.tabs)
    if "mode" in sets:
        following = parsed.mode is Mode.FOLLOW
        tabs = {t: s if s.instructor or s.following == following else TabState(s.name, following, s.lesson, s.step)
                for t, s in tabs.items()}
    new.tabs = tabs
    return new
