"""The commit-subject check of the pre-commit hook (scripts/check_commit_msg.py): `area: summary`, <= 72 characters."""

import subprocess
import sys

from hypothesis import given, settings
from hypothesis import strategies as st

from mantaray.paths import REPO

sys.path.insert(0, str(REPO / "scripts"))
import check_commit_msg as C  # noqa: E402

AREA = st.from_regex(r"[a-z][a-z0-9_]{0,8}", fullmatch=True)
WORDS = st.from_regex(r"[A-Za-z0-9][A-Za-z0-9 ,.'()-]{0,60}", fullmatch=True)


@settings(max_examples=200, derandomize=True)
@given(areas=st.lists(AREA, min_size=1, max_size=3), summary=WORDS)
def test_a_subject_of_areas_and_a_summary_holds_exactly_when_it_fits_72_characters(areas, summary):
    subject = f"{', '.join(areas)}: {summary}"
    assert (C.problem(subject + "\n\nbody\n") is None) == (len(subject) <= C.MAX_SUBJECT)


@settings(max_examples=200, derandomize=True)
@given(text=st.text(max_size=100))
def test_any_message_gets_an_answer_and_a_subject_without_an_area_is_refused(text):
    why = C.problem(text)
    assert why is None or why.startswith("the subject")
    if ":" not in text and "Merge " not in text and "Revert " not in text:  # no line can be a subject
        assert why is not None


def test_the_hook_reads_a_message_file_and_exits_1_with_one_line(tmp_path):
    long = tmp_path / "long"
    long.write_text("sim: " + "x" * 80 + "\n")
    ok = tmp_path / "ok"
    ok.write_text("# a git comment line\nfirmware: e-stop kept across resets\n")
    script = str(REPO / "scripts" / "check_commit_msg.py")
    bad = subprocess.run([sys.executable, script, str(long)], capture_output=True, text=True)
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "85 characters" in bad.stderr
    assert subprocess.run([sys.executable, script, str(ok)]).returncode == 0
