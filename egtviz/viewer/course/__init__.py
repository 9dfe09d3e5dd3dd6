"""The course: the start page and its preview, a lesson's panel, its lab and lens instruments."""
