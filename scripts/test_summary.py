#!/usr/bin/env python3
"""Summarises the JUnit XML files catkin writes and exits non-zero on any failure.

Prints one line per failing or skipped test case (a failure followed by the last lines of its
message), then a closing line
"tests: N passed, N failed, N skipped". A run with no result at all counts as a failure, as
does a test binary that crashed before writing its results (catkin writes a MISSING-*.xml).
"""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def main(root):
    passed = failed = skipped = 0
    files = sorted(glob.glob(os.path.join(root, "**", "*.xml"), recursive=True))
    for path in files:
        name = os.path.basename(path)
        try:
            tree = ET.parse(path)
        except ET.ParseError as err:
            print(f"FAILED  {name}: unreadable result file ({err})")
            failed += 1
            continue
        cases = tree.getroot().iter("testcase")
        for case in cases:
            label = f"{case.get('classname', '')}.{case.get('name', '')}"
            fault = case.find("failure")
            if fault is None:
                fault = case.find("error")
            if fault is not None:
                failed += 1
                print(f"FAILED  {name}: {label}")
                # The assertion's own words, so that a log's tail says why (CI keeps the tail).
                text = "\n".join(x for x in (fault.get("message"), fault.text) if x).strip()
                lines = text.splitlines()
                for line in lines[-25:]:
                    print(f"        {line[:300]}")
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                skipped += 1
                msg = case.find("skipped")
                why = (msg.get("message") or msg.text or "") if msg is not None else ""
                print(f"SKIPPED {name}: {label} {why.strip()[:160]}")
            else:
                passed += 1
        if name.startswith("MISSING"):
            failed += 1
            print(f"FAILED  {name}: the test produced no result (crashed or timed out)")
    if not files:
        print("FAILED  no test result files were written")
        failed += 1
    print(f"tests: {passed} passed, {failed} failed, {skipped} skipped")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "."))
