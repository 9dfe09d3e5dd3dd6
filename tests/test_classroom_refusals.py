"""The class's refusals reach the tab as refusals in their own words, not as "Something went wrong": a name the
course does not take (too long, control characters) and a question the class cannot keep."""

from types import SimpleNamespace

import pytest

from egtviz.classroom import Classroom, ClassroomError
from egtviz.lessons.progress import LearnerNameError
from egtviz.viewer.classroom.student_bar import notify_refusal


def _tab():
    shown = []
    return SimpleNamespace(add_notification=lambda title, body, **kw: shown.append((title, body))), shown


@pytest.mark.parametrize("name, reason", [("x" * 300, "at most 40 characters"), ("a\x00b", "control characters")])
def test_a_name_the_course_refuses_is_a_refusal_naming_the_field(name, reason):
    room = Classroom(None, token="t" * 20)
    with pytest.raises(LearnerNameError) as caught:
        room.join(1, name)
    client, shown = _tab()
    notify_refusal(client, caught.value)
    assert shown[0][0] == "Value refused"
    assert shown[0][1].startswith("your name: ") and reason in shown[0][1]


def test_a_question_the_class_cannot_keep_is_a_refusal_in_its_words():
    room = Classroom(None, token="t" * 20)
    with pytest.raises(ClassroomError) as caught:
        room.ask("<b>x</b>" * 200)
    client, shown = _tab()
    notify_refusal(client, caught.value)
    assert shown == [("Value refused", str(caught.value))] and "question" in shown[0][1]


def test_a_fault_of_the_program_still_hides_its_text():
    client, shown = _tab()
    notify_refusal(client, KeyError("/srv/secret/path"))
    assert shown[0][0] == "Something went wrong" and "/srv" not in shown[0][1]
