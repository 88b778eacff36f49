"""
The tiers (``tests/tiers.py``, applied by ``conftest.py``): an entry marks its tests slow, a
whole function or the parameter ids listed, and an entry that names no collected test is
reported, so that a renamed test cannot drop out of the list unseen; and the order conftest.py
gives the tests (by variant within each file).
"""

import tiers
from conftest import _tiers


class Item:
    """What ``_tiers`` uses of a collected test."""

    def __init__(self, nodeid):
        self.nodeid, self.markers = nodeid, []

    def add_marker(self, marker):
        self.markers.append(marker.name)


def items():
    return [Item(n) for n in ("t/a.py::test01", "t/a.py::test02[x-1]",
                              "t/a.py::test02[x-2]", "t/a.py::test02[y]",
                              "t/a.py::test02[y-3]",
                              "t/b.py::test01[/tmp/q/file]")]


def test01_whole_functions_and_listed_ids_are_marked():
    got = items()
    stale = _tiers(got, {"t/a.py": {"test01": tiers.WHOLE,
                                        "test02": (tiers.MORE, ["x-2", "y"])},
                         "t/b.py": {"test01": (tiers.MORE, ["/tmp/*"])}})
    assert stale == []
    assert [bool(i.markers) for i in got] == [True, False, True, True, False, True]


def test02_an_entry_naming_no_test_is_reported():
    stale = _tiers(items(), {"t/a.py": {"test03": tiers.DEEP,
                                            "test02": (tiers.MORE, ["z"])},
                             "t/c.py": {"test01": tiers.DEEP}})
    # a file not collected is not judged (a run of a few files)
    assert stale == ["t/a.py::test03", "t/a.py::test02[z]"]


def test03_every_reason_is_one_of_the_three():
    for entries in tiers.SLOW.values():
        for entry in entries.values():
            reason = entry[0] if isinstance(entry, tuple) else entry
            assert reason in (tiers.WHOLE, tiers.MORE, tiers.DEEP)


class Case(Item):
    """A collected test with the parameters and fixtures ``_variant`` reads."""

    def __init__(self, nodeid, variant=None, fixture=None):
        super().__init__(nodeid)
        self.callspec = type("CallSpec", (), {"params": {"variant": variant}})() \
            if variant else None
        self.fixturenames = [f"variant_{fixture}"] if fixture else []


def test04_tests_run_file_by_file_grouped_by_variant():
    """Files keep their order; within one, the tests go by variant, the order of the rest
    kept (so that Mitsuba switches variants a few times per file, not at every case)."""
    from conftest import _by_variant

    got = [Case("t/b.py::t1[scalar_rgb]", "scalar_rgb"), Case("t/b.py::t1[llvm_ad_rgb]",
                                                              "llvm_ad_rgb"),
           Case("t/b.py::t2", fixture="scalar_rgb"), Case("t/b.py::t3"),
           Case("t/a.py::t1[llvm_ad_rgb]", "llvm_ad_rgb"), Case("t/a.py::t2")]
    _by_variant(got)
    assert [c.nodeid for c in got] == [
        "t/b.py::t3", "t/b.py::t1[llvm_ad_rgb]", "t/b.py::t1[scalar_rgb]", "t/b.py::t2",
        "t/a.py::t2", "t/a.py::t1[llvm_ad_rgb]"]
