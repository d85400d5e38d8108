#!/usr/bin/env python3
"""Count JUnit XML results (gtest, rostest, pytest) and print `N passed, M failed`.

Usage: test_summary.py [--phases TSV] [--slowest N] [--seed S] DIR [DIR ...]. Exits 1 on any
failure or when nothing passed. A `MISSING-*.xml` (a rostest that never wrote results) or a
`BUILD-FAILED` marker counts as a failure. Under the closing line: the wall time of each phase
(TSV lines `name<TAB>seconds`), the N slowest test cases and rostest files (JUnit `time`), and
the test-order seed.
"""

import argparse
import os
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
            if label.startswith("__main__.") or not case.get("classname"):
                # a rostest node's unittest names its class __main__: say which file it was
                label = "%s: %s" % (os.path.splitext(name)[0], label)
            bad = case.find("failure")
            if bad is None:
                bad = case.find("error")
            if bad is not None:
                failed += 1
                reason = (bad.get("message") or bad.text or "").strip().splitlines()
                names.append(label + (" -- " + reason[0][:200] if reason else ""))
            elif case.find("skipped") is not None:
                skipped += 1
            else:
                passed += 1
    return passed, failed, skipped, names


def timings(path):
    """Return ([(seconds, test case label)], (seconds, file label) or None) of one JUnit XML file."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError:
        return [], None
    suites = [root] if root.tag == "testsuite" else root.findall("testsuite")
    cases = []
    for suite in suites:
        for case in suite.findall("testcase"):
            try:
                label = "%s.%s" % (case.get("classname", ""), case.get("name", ""))
                cases.append((float(case.get("time", 0.0)), label))
            except ValueError:
                continue
    name = os.path.basename(path)
    whole = None
    if name.startswith("rostest-"):  # catkin's result of one .test file
        try:
            whole = (sum(float(s.get("time", 0.0)) for s in suites), "%s/%s" % (os.path.basename(os.path.dirname(path)),
                                                                                name[len("rostest-"):-len(".xml")]))
        except ValueError:
            whole = None
    return cases, whole


def print_report(phases, slowest, seed, cases, rostests):
    """The lines under the closing line: phases, slowest tests and rostests, seed."""
    if phases and os.path.exists(phases):
        print("wall time per phase:")
        with open(phases) as f:
            for line in f:
                name, _, seconds = line.rstrip("\n").partition("\t")
                if seconds:
                    print("  %7.0f s  %s" % (float(seconds), name))
    if slowest:
        print("slowest %d tests:" % slowest)
        for seconds, label in sorted(cases, reverse=True)[:slowest]:
            print("  %7.1f s  %s" % (seconds, label))
        if rostests:
            print("slowest %d rostest files (time rostest reports for the file):" % slowest)
            for seconds, label in sorted(rostests, reverse=True)[:slowest]:
                print("  %7.1f s  %s" % (seconds, label))
    if seed:
        print("test order seed %s (RBD_TEST_SEED=%s repeats it)" % (seed, seed))


def main(dirs, phases=None, slowest=0, seed=None):
    """Walk the directories and print the closing line (and the timing report under it)."""
    passed = failed = skipped = 0
    failures = []
    cases, rostests = [], []
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
                    file_cases, whole = timings(os.path.join(dirpath, f))
                    cases.extend(file_cases)
                    if whole:
                        rostests.append(whole)
    for name in failures:
        print("FAILED: %s" % name)
    line = "%d passed, %d failed" % (passed, failed)
    if skipped:
        line += ", %d skipped" % skipped
    print(line)
    print_report(phases, slowest, seed, cases, rostests)
    return 1 if failed or passed == 0 else 0


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description="N passed, M failed from JUnit XML files")
    ap.add_argument("dirs", nargs="*", default=["test-results"])
    ap.add_argument("--phases", help="TSV of phase name and wall seconds, printed under the closing line")
    ap.add_argument("--slowest", type=int, default=0, help="print the N slowest tests and rostest files")
    ap.add_argument("--seed", help="the test-order seed of the run")
    a = ap.parse_args()
    raise SystemExit(main(a.dirs, a.phases, a.slowest, a.seed))
