# SPDX-License-Identifier: GPL-3.0-or-later
"""Runs the msii program for the algorithms: finds it, turns what it writes on stderr into
Processing feedback, and stops it on Cancel.

The algorithms call the program rather than msii's Python module, as QGIS's GDAL and SAGA
providers call theirs, for three reasons:
- the files are the command line's, bit for bit, by construction: the same code writes them;
- Cancel stops the work at once: the process is terminated, and msii removes its temporary
  files on SIGTERM; it writes each output under a temporary name and renames it at the end,
  so a cancelled run leaves no output behind;
- the plugin does not depend on QGIS's Python matching the one the module was built for.
"""

import glob
import os
import queue
import re
import shlex
import shutil
import subprocess
import threading

from qgis.core import QgsProcessingException, QgsProcessingFeedback

# The name of the provider setting "msii program" (Processing options ▸ Providers ▸ msii).
PROGRAM_SETTING = "MSII_PROGRAM"
# Written by `cmake --install` next to __init__.py: the absolute path of the installed program.
PROGRAM_FILE = os.path.join(os.path.dirname(__file__), "msii_program.txt")

# msii's lines on stderr with --progress-lines (docs/cli.md): "msii: progress 42.0 V and S, level 1".
_PROGRESS = re.compile(r"msii: progress (\d+(?:\.\d*)?) (.*)$")
_WARNING = "msii: warning: "
_ERROR = "msii: error: "

# How long a terminated msii may take to remove its temporary files and exit before it is killed.
_TERMINATE_SECONDS = 10.0
# How often the Cancel button is looked at while msii is silent.
_POLL_SECONDS = 0.1


def _executable(path):
    return os.path.isfile(path) and os.access(path, os.X_OK)


def configured_program():
    """The provider setting "msii program" ("" when unset, or without Processing's Python)."""
    try:
        from processing.core.ProcessingConfig import ProcessingConfig
    except ImportError:
        return ""
    return ProcessingConfig.getSetting(PROGRAM_SETTING) or ""


def find_program(configured=""):
    """The msii program: @p configured (the provider setting), else $MSII_EXE, else the path in
    msii_program.txt, else `msii` on the PATH. A place that is set but holds no program is an
    error, not skipped: another msii found further on would run silently instead."""
    candidates = [
        (configured or "", "the setting Processing options ▸ Providers ▸ msii ▸ msii program"),
        (os.environ.get("MSII_EXE", ""), "the environment variable MSII_EXE"),
    ]
    if os.path.isfile(PROGRAM_FILE):
        with open(PROGRAM_FILE, encoding="utf-8") as f:
            candidates.append((f.read().strip(), PROGRAM_FILE + " (written by cmake --install)"))
    for path, where in candidates:
        if not path:
            continue
        path = os.path.expanduser(path)
        if not _executable(path):
            raise QgsProcessingException(
                f"The msii program '{path}' named by {where} does not exist or is not executable.")
        return path
    on_path = shutil.which("msii")
    if on_path:
        return on_path
    raise QgsProcessingException(
        "The msii program was not found. Set its path in Processing options ▸ Providers ▸ msii ▸ "
        "msii program (or in the environment variable MSII_EXE), or put msii on the PATH "
        "(cmake --install installs it into <prefix>/bin).")


def _read_lines(stream, name, lines):
    """Puts each line of @p stream on @p lines as (name, line), then (name, None) at its end."""
    for line in iter(stream.readline, ""):
        lines.put((name, line.rstrip("\r\n")))
    lines.put((name, None))


def _remove_temporaries(pid, folders):
    """Removes msii's temporary files in @p folders (`.NAME.tmp-PID-N`, engine/src/io/atomic_file.cpp):
    msii removes them itself on SIGTERM; this is for a process that had to be killed."""
    for folder in folders:
        for path in glob.glob(os.path.join(glob.escape(folder), f".*.tmp-{pid}-*")):
            try:
                os.remove(path)
            except OSError:
                pass


def run(arguments, feedback, outputs=()):
    """Runs `msii ARGUMENTS --overwrite --progress-lines`, reporting to @p feedback, and checks
    that it wrote @p outputs.

    --overwrite: Processing chooses the outputs, and its temporary outputs may exist already.
    Not --quiet, which would suppress the warnings, and not -j: msii uses every core.

    @throw QgsProcessingException with msii's error line when it fails, or when Cancel stopped it.
    """
    if feedback is None:
        feedback = QgsProcessingFeedback()
    command = [find_program(configured_program())] + [str(a) for a in arguments]
    command += ["--overwrite", "--progress-lines"]
    feedback.pushCommandInfo(shlex.join(command))

    with subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, encoding="utf-8", errors="replace",
                          bufsize=1) as process:
        status, errors, others = _report(process, feedback, outputs)

    if status != 0:
        if errors:
            raise QgsProcessingException("\n".join(errors))
        if status < 0:
            raise QgsProcessingException(f"msii was stopped by signal {-status}.")
        # Wrong usage (status 2) is CLI11's message, not an "msii: error:" line.
        tail = "\n".join(others[-5:])
        raise QgsProcessingException(f"msii failed (exit status {status}){': ' + tail if tail else '.'}")
    for path in outputs:
        if not os.path.isfile(path):
            raise QgsProcessingException(f"msii finished without writing '{path}'.")


def _report(process, feedback, outputs):
    """Reports what @p process writes until it ends; returns its exit status, its error lines
    and its other lines. Stops it on Cancel."""
    # One reader per stream, so that neither pipe fills while the other is read; the loop
    # below reports from this thread, which Processing gave the algorithm, and looks at the
    # Cancel button while msii is silent.
    lines = queue.Queue()
    readers = [threading.Thread(target=_read_lines, args=(stream, name, lines), daemon=True)
               for stream, name in ((process.stderr, "stderr"), (process.stdout, "stdout"))]
    for reader in readers:
        reader.start()

    errors, others, stage, open_streams, completed = [], [], None, len(readers), False
    try:
        while open_streams:
            if feedback.isCanceled() and not completed:
                _stop(process, outputs)
                if process.returncode != 0:
                    raise QgsProcessingException("Cancelled: msii was stopped; it wrote no output.")
                completed = True  # msii had finished when Cancel came: its outputs stand
            try:
                name, line = lines.get(timeout=_POLL_SECONDS)
            except queue.Empty:
                continue
            if line is None:
                open_streams -= 1
                continue
            progress = _PROGRESS.match(line) if name == "stderr" else None
            if progress:
                if progress.group(2) != stage:
                    stage = progress.group(2)
                    feedback.setProgressText(stage)
                feedback.setProgress(float(progress.group(1)))
            elif line.startswith(_WARNING):
                feedback.pushWarning(line)
            elif line.startswith(_ERROR):
                errors.append(line)
            elif line:
                others.append(line)
                feedback.pushConsoleInfo(line)
        return process.wait(), errors, others
    finally:
        if process.poll() is None:  # an exception from the feedback: do not leave msii running
            _stop(process, outputs)
        for reader in readers:
            reader.join(timeout=1.0)


def _stop(process, outputs):
    """Terminates @p process and waits for it; kills it if it does not exit in time, and then
    removes the temporary files it may have left in the folders of @p outputs."""
    process.terminate()
    try:
        process.wait(timeout=_TERMINATE_SECONDS)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
    folders = {os.path.dirname(os.path.abspath(p)) for p in outputs}
    _remove_temporaries(process.pid, folders)
