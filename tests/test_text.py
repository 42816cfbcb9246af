from activevision.text import counted


def test_counted_says_one_in_the_singular_and_the_rest_in_the_plural():
    assert [counted(n, "match") for n in (0, 1, 2)] == ["0 matches", "1 match", "2 matches"]
    assert [counted(n, "tick") for n in (1, 300)] == ["1 tick", "300 ticks"]
    assert counted("1", "step") == "1 step" and counted("20", "step") == "20 steps"  # CSV cells
    assert counted(2, "box") == "2 boxes"


def test_the_match_command_counts_its_methods_and_matches_so():
    # its figures' titles and printed header read "1 methods x 1 matches"
    from activevision.cli import match

    assert match.counted is counted
