"""pose_io.contacts: which ankles touch the ground, on the synthetic walk of the cleanup's tests."""

from pose_io.contacts import contact_window, foot_contacts
from tests.pose_io.test_feet import BODY15, walk


def test_the_window_is_the_odd_frame_count_nearest_a_second():
    assert [contact_window(f) for f in (30, 29.97, 25, 24, 60, 1)] == [31, 31, 25, 25, 61, 1]


def test_foot_contacts_of_a_planted_and_a_lifted_foot():
    joints, contacts = walk(slide=0.0)
    found = foot_contacts(joints, 150.0, BODY15, window=31)
    assert (found[contacts]).mean() > 0.95  # every planted frame touches
