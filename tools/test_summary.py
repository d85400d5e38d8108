#!/usr/bin/env python3
"""Count JUnit XML results (gtest, rostest, pytest) and print `N passed, M failed`.

Usage: test_summary.py DIR [DIR ...]. Exits 1 on any failure or when nothing passed.
A `MISSING-*.xml` (a rostest that never wrote results) or a `BUILD-FAILED` marker counts
as a failure.
"""

import os
import sys
import xml.etree.ElementTree as ET


def count_file(path):
    """Return (passed, failed, skipped, failed_names) for one JUnit XML file."""
    name = os.path.basename(path)
    if name.startswith("MISSING-"):
        return 0, 1, 0, [name]
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        return 0, 1, 0, ["%s (unparsable: %s)" % (name, exc)]
    suites = [root] if root.tag == "testsuite" else root.findall("testsuite")
    passed = failed = skipped = 0
    names = []
    for suite in suites:
        cases = suite.findall("testcase")
        if not cases:
            # rostest writes a suite without cases when the test node never ran.
            errs = int(suite.get("errors", 0)) + int(suite.get("failures", 0))
            if errs:
                failed += errs
                names.append("%s: %s" % (name, suite.get("name")))
            continue
        for case in cases:
            label = "%s.%s" % (case.get("classname", ""), case.get("name", ""))
            if case.find("failure") is not None or case.find("error") is not None:
                failed += 1
                names.append(label)
            elif case.find("skipped") is not None:
                skipped += 1
            else:
                passed += 1
    return passed, failed, skipped, names


def main(dirs):
    """Walk the directories and print the closing line."""
    passed = failed = skipped = 0
    failures = []
    for top in dirs:
        for dirpath, _dirs, files in os.walk(top):
            if "BUILD-FAILED" in files:
                failed += 1
                failures.append("build failed (%s)" % os.path.join(dirpath, "BUILD-FAILED"))
            for f in sorted(files):
                if f.endswith(".xml"):
                    p, fl, s, names = count_file(os.path.join(dirpath, f))
                    passed += p
                    failed += fl
                    skipped += s
                    failures.extend(names)
    for name in failures:
        print("FAILED: %s" % name)
    line = "%d passed, %d failed" % (passed, failed)
    if skipped:
        line += ", %d skipped" % skipped
    print(line)
    return 1 if failed or passed == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:] or ["test-results"]))
