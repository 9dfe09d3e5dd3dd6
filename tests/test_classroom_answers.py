"""Answers: the latest per student counts, histograms of numbers and of texts (no names), a flood from one
student costs O(1) per answer, and concurrent joins and answers lose nothing."""

from __future__ import annotations

import threading
import tracemalloc

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.classroom import AnswersChanged, Classroom, ClassroomError, Histogram
from egtviz.classroom.answers import EVENT_INTERVAL_S

from _waiting import PATIENCE


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _room(n, clock=None):
    room = Classroom(task_count=lambda lesson: 0, clock=clock or Clock())
    for i in range(n):
        room.join(i, f"student {i}")
    return room


def test_histogram_of_numbers_counts_the_latest_answer_of_each_student():
    room = _room(5)
    for tab, value in enumerate([1.0, 2.0, 2.5, 9.0, 10.0]):
        room.record_answer(tab, "depth", value)
    room.record_answer(4, "depth", 1.0)  # changed their mind: 10 no longer counts
    h = room.histogram("depth", bins=4)
    assert h.edges == (1.0, 3.0, 5.0, 7.0, 9.0)
    assert h.counts == (4, 0, 0, 1)
    assert (h.n, h.categories, h.version) == (5, (), 6)


def test_histogram_of_texts_folds_case_and_sorts_by_count():
    room = _room(5)
    for tab, value in enumerate(["Parallel", "parallel ", "meet", "  PARALLEL", "Meet"]):
        room.record_answer(tab, "lines?", value)
    h = room.histogram("lines?")
    assert h.categories == (("parallel", 3), ("meet", 2))
    assert (h.edges, h.counts, h.n) == ((), (), 5)


def test_one_number_makes_one_unit_wide_range_and_mixed_answers_split():
    room = _room(3)
    room.record_answer(0, "q", 4)
    room.record_answer(1, "q", 4.0)
    room.record_answer(2, "q", "don't know")
    h = room.histogram("q", bins=2)
    assert h.edges == (3.5, 4.0, 4.5)
    assert h.counts == (0, 2)
    assert h.categories == (("don't know", 1),)
    assert h.n == 3


def test_histogram_holds_no_names():
    room = _room(2)
    room.record_answer(0, "q", 1.0)
    room.record_answer(1, "q", "student 0")  # a text answer is an answer, not a name of someone
    h = room.histogram("q")
    assert isinstance(h, Histogram)
    assert set(Histogram.__dataclass_fields__) == {"question", "edges", "counts", "categories", "n", "version"}
    assert "student 1" not in repr(h)


def test_an_unasked_question_has_an_empty_histogram():
    assert _room(0).histogram("nobody asked") == Histogram("nobody asked", (), (), (), 0, 0)


@pytest.mark.parametrize("value, match", [(float("nan"), "finite"), (float("inf"), "finite"), (True, "number or text"),
                                          (None, "number or text"), ("", "empty"), ("x" * 81, "at most 80"),
                                          ("a\x00b", "control")])
def test_bad_answers_are_refused(value, match):
    room = _room(1)
    with pytest.raises(ClassroomError, match=match):
        room.record_answer(0, "q", value)
    assert room.histogram("q").n == 0


def test_an_answer_from_no_student_is_refused():
    room = _room(0)
    room.instructor_join(9)
    with pytest.raises(ClassroomError, match="no student"):
        room.record_answer(9, "q", 1.0)


def test_bins_are_checked():
    with pytest.raises(ClassroomError, match="bins"):
        _room(0).histogram("q", bins=0)


def test_a_flood_from_one_student_is_thinned_and_costs_no_memory():
    clock = Clock()
    room = _room(2, clock)
    events = []
    room.subscribe(events.append)
    tracemalloc.start()
    room.record_answer(0, "q", 0.0)
    before = tracemalloc.get_traced_memory()[0]
    for i in range(20_000):
        room.record_answer(0, "q", float(i))
    grown = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    assert grown < 20_000  # a replaced entry, not a list of 20,000 answers (bytes)
    assert events == [AnswersChanged("q")]  # the clock did not move: one event, the flood's others thinned
    room.record_answer(1, "q", 5.0)  # another student is not thinned by the first one's flood
    assert events == [AnswersChanged("q")] * 2
    clock.now += EVENT_INTERVAL_S
    room.record_answer(0, "q", 1.0)
    assert len(events) == 3
    h = room.histogram("q", bins=1)
    assert (h.n, h.counts, h.version) == (2, (2,), 20_003)
    assert h.edges == (1.0, 5.0)  # the flood's latest answer (1.0) is the one that counts


def test_concurrent_joins_and_answers_lose_nothing():
    room = Classroom(task_count=lambda lesson: 0)
    threads, per_thread = 8, 50

    def work(k: int) -> None:
        for i in range(per_thread):
            tab = k * per_thread + i
            room.join(tab, f"s{tab}")
            room.record_answer(tab, "q", float(tab % 10))
            room.record_answer(tab, "t", "abc"[tab % 3])

    pool = [threading.Thread(target=work, args=(k,)) for k in range(threads)]
    for t in pool:
        t.start()
    for t in pool:
        t.join(PATIENCE)
        assert not t.is_alive(), f"waited {PATIENCE:.0f} s for a thread's joins and answers (a deadlock?)"
    n = threads * per_thread
    assert len(room.roster()) == n
    h = room.histogram("q", bins=10)
    assert h.n == n and sum(h.counts) == n and h.counts == (n // 10,) * 10
    assert dict(room.histogram("t").categories) == {"a": 134, "b": 133, "c": 133}


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 9), st.floats(-1e6, 1e6, allow_nan=False)), max_size=60),
       st.integers(1, 20))
def test_histogram_counts_each_students_last_answer(answers, bins):
    room = _room(10)
    last = {}
    for tab, value in answers:
        room.record_answer(tab, "q", value)
        last[tab] = value
    h = room.histogram("q", bins=bins)
    assert h.n == len(last) and sum(h.counts) == len(last)
    if last:
        expected, _ = np.histogram(list(last.values()), bins=len(h.counts), range=(h.edges[0], h.edges[-1]))
        assert h.counts == tuple(int(c) for c in expected)
        assert h.edges[0] <= min(last.values()) and h.edges[-1] >= max(last.values())


def test_ask_a_question_and_read_answers_by_name():
    from egtviz.classroom import QuestionAsked

    room = _room(2)
    events = []
    room.subscribe(events.append)
    assert room.asked() is None
    room.ask("  Where do the lines meet? ")
    room.ask("Where do the lines meet?")
    assert room.asked() == "Where do the lines meet?"
    room.record_answer(0, "Where do the lines meet?", "At the epipole")
    room.record_answer(1, "Where do the lines meet?", 3)
    assert room.answers("Where do the lines meet?") == {"student 0": "at the epipole", "student 1": 3.0}
    assert room.answers("unknown") == {}
    room.ask(None)
    assert room.asked() is None
    assert [e for e in events if isinstance(e, QuestionAsked)] == [QuestionAsked("Where do the lines meet?"),
                                                                   QuestionAsked(None)]
    assert Classroom.from_json(room.to_json()).asked() is None
    room.ask("again?")
    assert Classroom.from_json(room.to_json()).asked() == "again?"
