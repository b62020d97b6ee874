# Copyright 2026 digital_actor_planner developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""Python side of driver.js: one headless Debian chromium page, driven by JSON lines."""
import json
import os
import queue
import shutil
import subprocess
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
CHROMIUM = os.environ.get('CHROMIUM', '/usr/bin/chromium')
PAD_UV = (0.3, 0.78)   # where the viewer draws the drag pad, as a fraction of the 3D view


def missing_tools():
    """Names of what the browser tests need and this machine lacks (empty when all is there)."""
    missing = []
    if not os.path.exists(CHROMIUM):
        missing.append(f'chromium ({CHROMIUM})')
    if shutil.which('node') is None:
        missing.append('node')
    if not os.path.isdir(os.path.join(HERE, 'node_modules', 'playwright-core')):
        missing.append('playwright-core (run: npm ci in test/browser)')
    return missing


class ChromiumPage:
    """A headless chromium page with a fresh profile; stop() ends the browser by PID."""

    def __init__(self, log_path=None):
        self.profile = tempfile.mkdtemp(prefix='dap-chromium-')
        self._log = open(log_path, 'w') if log_path else subprocess.DEVNULL
        self.proc = subprocess.Popen(['node', os.path.join(HERE, 'driver.js'), self.profile],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=self._log, text=True, start_new_session=True)
        self._replies = queue.Queue()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.proc.stdout:
            self._replies.put(line)
        self._replies.put(None)

    def send(self, timeout=180.0, **command):
        """Run one driver command; returns its reply dict, raises RuntimeError on failure."""
        self.proc.stdin.write(json.dumps(command) + '\n')
        self.proc.stdin.flush()
        try:
            line = self._replies.get(timeout=timeout)
        except queue.Empty:
            raise RuntimeError(f'browser did not answer {command} within {timeout} s')
        if line is None:
            raise RuntimeError(f'browser driver exited during {command}')
        reply = json.loads(line)
        if not reply.get('ok'):
            raise RuntimeError(f'browser command {command} failed: {reply.get("error")}')
        return reply

    # Named after the driver's command it sends.
    def open(self, url):  # noqa: A003
        self.send(cmd='open', url=url, timeout=240.0)

    def text(self):
        return self.send(cmd='text')['text']

    def wait_for_text(self, fragment, timeout):
        """Poll the page's text until it contains ``fragment``; returns the last text seen."""
        deadline = time.monotonic() + timeout
        text = ''
        while time.monotonic() < deadline:
            text = self.text()
            if fragment in text:
                return text
            time.sleep(0.3)
        return text

    def screenshot(self, path):
        self.send(cmd='screenshot', path=path, timeout=240.0)

    def pad_center(self):
        box = self.send(cmd='canvas')['box']
        return (box['x'] + PAD_UV[0] * box['width'], box['y'] + PAD_UV[1] * box['height'])

    def press(self, x, y):
        self.send(cmd='mouse', action='down', x=x, y=y)

    def move_to(self, start, end, steps=4, pause=0.05):
        """Move the pointer like a hand does: small steps with a short pause between them."""
        for k in range(1, steps + 1):
            f = k / steps
            self.send(cmd='mouse', action='move', x=start[0] + f * (end[0] - start[0]),
                      y=start[1] + f * (end[1] - start[1]))
            time.sleep(pause)

    def release(self):
        self.send(cmd='mouse', action='up')

    def select(self, label, option):
        self.send(cmd='select', label=label, option=option)

    def click(self, name):
        """Click the button labelled ``name``."""
        self.send(cmd='click', name=name)

    def camera_reports(self):
        """
        Return the camera poses the page reported to the viewer since the last call.

        The camera poses the page reported to the viewer since the last call, oldest first: viser's
        ViewerCameraMessage as a dict (position, look_at in world metres, wxyz from the camera's
        OpenCV frame to the world, fov (vertical, rad), image_width, image_height).
        """
        import base64
        import msgspec
        reports = []
        for payload in self.send(cmd='sent')['frames']:
            try:
                message = msgspec.msgpack.decode(base64.b64decode(payload))
            except msgspec.DecodeError:
                continue
            if isinstance(message, dict) and message.get('type') == 'ViewerCameraMessage':
                reports.append(message)
        return reports

    def wait_for_text_gone(self, fragment, timeout):
        """Poll the page's text until ``fragment`` is not in it; returns the last text seen."""
        deadline = time.monotonic() + timeout
        text = self.text()
        while fragment in text and time.monotonic() < deadline:
            time.sleep(0.3)
            text = self.text()
        return text

    def stop(self):
        if self.proc.poll() is None:
            try:
                self.proc.stdin.write(json.dumps({'cmd': 'close'}) + '\n')
                self.proc.stdin.flush()
                self.proc.wait(timeout=15)
            except (OSError, subprocess.TimeoutExpired):
                try:
                    os.killpg(self.proc.pid, 9)
                except ProcessLookupError:
                    pass
                self.proc.wait(timeout=10)
        if self._log is not subprocess.DEVNULL:
            self._log.close()
        shutil.rmtree(self.profile, ignore_errors=True)


def not_blank(png_path):
    """Return true when a screenshot shows a rendered scene: many colours, not one flat fill."""
    from PIL import Image
    import numpy as np
    image = np.asarray(Image.open(png_path).convert('RGB'), dtype=np.int32)
    colours = len(np.unique(image.reshape(-1, 3) // 8, axis=0))
    return colours > 50 and float(image.std()) > 10.0
