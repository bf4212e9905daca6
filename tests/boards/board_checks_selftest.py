#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The check of run_e2e.py's board checks, without an emulator: a board's
measures as its harness writes them pass, and each broken promise fails
(every limit of BOARDS broken on its own, a tick rate that is not HELLO's, a
missing measure); a servo pen's pulses at the profile's widths one period
apart pass, and a wrong width, a missed period, a pen that never went down,
a header with other widths, or an ENABLE that starts active fail.

  board_checks_selftest.py   (run_e2e.py beside it)
"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import run_e2e  # noqa: E402

# Measures of real plain runs (the keys the limits read, values as measured).
GOOD = {
    "mega2560-ramps": {"tick_hz": 2000, "late_ticks": 0, "lost_ticks": 0, "watchdog_resets": 0,
                       "boots": 1, "stack_high_water": 2301, "ram_never_used": 815},
    "microbit-v1": {"tick_hz": 20000, "fault": 0, "late_moving_ticks": 0, "rx_overruns": 0,
                    "uart_errors": 0, "stack_high_water_bytes": 2668,
                    "stack_space_bytes": 7072, "servo_periods": 546, "servo_max_lateness_us": 2,
                    "emulated_s": 10.946},
}
# Limits whose value is not one measure: how to break them.
DERIVED = {"stack margin": {"stack_high_water_bytes": 7000},
           "servo periods missing": {"servo_periods": 544}}

failures = []


def expect(what, passes, check):
    """Runs `check`; records a failure unless it passed (or failed) as expected."""
    try:
        check()
        outcome = True
    except run_e2e.Failure as failure:
        outcome = False
        detail = str(failure)
    if outcome != passes:
        failures.append("%s: %s" % (what, "passed" if outcome else "failed: " + detail))
    elif not passes:
        print("caught: %s: %s" % (what, detail))


def breaking(limit, measures):
    """`measures` with the one value changed that breaks `limit`."""
    if limit.label in DERIVED:
        return dict(measures, **DERIVED[limit.label])
    step = {"==": 1, ">=": -1, "<=": 1}[limit.op]
    return dict(measures, **{limit.label: limit.bound + step})


def check_limits():
    for board, good in GOOD.items():
        limits = run_e2e.BOARDS[board]["limits"]
        hello = good["tick_hz"]
        for scenario in run_e2e.SCENARIOS:
            expect("%s %s: its measures" % (board, scenario), True,
                   lambda s=scenario: run_e2e.check_measures(good, limits, s, hello, "good"))
        for limit in limits:
            bad = breaking(limit, good)
            expect("%s: %s broken" % (board, limit.label), False,
                   lambda m=bad, s=limit.scenarios[0]: run_e2e.check_measures(
                       m, limits, s, hello, "perturbed"))
        expect("%s: HELLO says another tick rate" % board, False,
               lambda: run_e2e.check_measures(good, limits, "plain", hello // 2, "good"))
        missing = {k: v for k, v in good.items() if k != limits[0].label}
        expect("%s: a measure missing" % board, False,
               lambda: run_e2e.check_measures(missing, limits, "plain", hello, "missing"))


def servo_waveform(widths_us, gaps_ns=None, enable_start=1, pen="servo 1000 2000",
                   board="mega2560-ramps"):
    """A Mega's or micro:bit's recording: ENABLE lines, then one servo pulse
    per width (µs; a float for a width off by a fraction)."""
    lines = ["# fdsurf-waveform 1", "# board %s" % board, "# dir_negative_level 1",
             "# enable_active_level 0", "# pen %s" % pen,
             "0 X_EN %d" % enable_start, "0 Y_EN 1", "0 SERVO 0"]
    time_ns = 1_000_000
    for i, width in enumerate(widths_us):
        lines.append("%d SERVO 1" % time_ns)
        lines.append("%d SERVO 0" % (time_ns + round(width * 1000)))
        time_ns += (gaps_ns or {}).get(i, run_e2e.SERVO_PERIOD_NS)
    return "\n".join(lines) + "\n"


def check_pins(workdir):
    good = [1000] * 5 + [2000] * 5 + [1000] * 3
    cases = [
        ("a servo pen at 1000/2000 us every 20 ms", True, servo_waveform(good)),
        ("a 1500 us servo pulse", False, servo_waveform(good[:6] + [1500] + good[7:])),
        ("servo pulses 25 ms apart", False, servo_waveform(good, gaps_ns={4: 25_000_000})),
        ("a pen that never went down", False, servo_waveform([1000] * 8)),
        ("a header with other widths", False, servo_waveform(good, pen="servo 900 2100")),
        ("an ENABLE that starts active", False, servo_waveform(good, enable_start=0)),
    ]
    # The CONFIG's widths 1200/1800: the image's 1000 (pen up) only before them.
    job = [1000] * 2 + [1200] * 3 + [1800] * 5 + [1200] * 3
    job_cases = [
        ("the CONFIG's 1200/1800 us after the image's pen-up 1000", True, servo_waveform(job)),
        ("the image's 2000 us after the CONFIG", False, servo_waveform(job[:7] + [2000] + job[8:])),
        ("the image's 1000 us after the CONFIG", False, servo_waveform(job[:4] + [1000] + job[5:])),
        ("the image's widths only (the CONFIG ignored)", False, servo_waveform(good)),
    ]
    # The micro:bit's CI job as recorded (widths 999.7..1800.7 us, periods
    # 19 999.8..20 000.9 us), and what its TIMER1 servo could get wrong: an
    # edge late by a masked section (3 us), a period lost, the pulse cut by
    # a width set mid-pulse.
    microbit = [1000] * 2 + [1200] * 3 + [1800] * 5 + [1200] * 3
    microbit_cases = [
        ("micro:bit: the CONFIG's 1200/1800 us", True,
         servo_waveform(microbit, board="microbit-v1")),
        ("micro:bit: widths 0.7 us off (as recorded)", True,
         servo_waveform([999.7, 1000.8] + [1200.7] * 3 + [1800.7] * 5 + [1199.8] * 3,
                        board="microbit-v1")),
        ("micro:bit: a 1803 us pulse (a late edge)", False,
         servo_waveform(microbit[:6] + [1803] + microbit[7:], board="microbit-v1")),
        ("micro:bit: a period lost (40 ms)", False,
         servo_waveform(microbit, gaps_ns={5: 40_000_000}, board="microbit-v1")),
        ("micro:bit: a pulse cut to 1500 us", False,
         servo_waveform(microbit[:5] + [1500] + microbit[6:], board="microbit-v1")),
        ("micro:bit: the pen never went down", False,
         servo_waveform([1000] * 2 + [1200] * 8, board="microbit-v1")),
    ]
    for job_us, case_list in ((None, cases), ((1200, 1800), job_cases),
                              ((1200, 1800), microbit_cases)):
        for what, passes, text in case_list:
            path = os.path.join(workdir, "case.wave")
            with open(path, "w") as f:
                f.write(text)

            def check(p=path, j=job_us):
                header, transitions = run_e2e.read_transitions(p)
                run_e2e.check_enable_released(header, transitions)
                run_e2e.check_servo(header, transitions, (1000, 2000), j)
            expect(what, passes, check)


def main():
    check_limits()
    with tempfile.TemporaryDirectory() as workdir:
        check_pins(workdir)
        path = os.path.join(workdir, "measures.tsv")
        with open(path, "w") as f:
            f.write("measure\tvalue\tunit\nlate_ticks\t0\tticks\nboots\tone\tstarts\n")
        expect("a measures TSV with a value that is no number", False,
               lambda: run_e2e.read_measures(path))
    for failure in failures:
        print("FAIL: %s" % failure)
    print("board_checks_selftest: %s" % ("FAIL" if failures else "PASS"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
