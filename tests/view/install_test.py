#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""`cmake --install` into a temporary prefix, then the installed `harap view` serves its page
from the install tree: `/`, a script and a vendored library, and nothing outside them.

    install_test.py CMAKE BUILD_DIR SCENARIO
"""
import pathlib
import re
import signal
import subprocess
import sys
import tempfile
import urllib.error
import urllib.request


def fetch(url):
    try:
        with urllib.request.urlopen(url, timeout=30) as response:
            return response.status, response.read()
    except urllib.error.HTTPError as error:
        return error.code, b""


def main():
    cmake, build, scenario = sys.argv[1:4]
    with tempfile.TemporaryDirectory(prefix="harap-install-") as prefix:
        subprocess.run([cmake, "--install", build, "--prefix", prefix], check=True,
                       stdout=subprocess.DEVNULL)
        prefix = pathlib.Path(prefix)
        harap = prefix / "bin" / "harap"
        page = prefix / "share" / "harap" / "view"
        assert harap.is_file(), f"{harap} was not installed"
        assert (page / "index.html").is_file(), f"{page}/index.html was not installed"
        # A mark only the installed copy has: the page must come from the install tree.
        mark = "<!-- installed copy -->"
        with open(page / "index.html", "a", encoding="utf-8") as index:
            index.write(mark + "\n")
        server = subprocess.Popen([str(harap), "view", scenario, "--port", "0"], cwd=prefix,
                                  stdout=subprocess.PIPE, text=True)
        try:
            line = server.stdout.readline()
            match = re.search(r"http://127\.0\.0\.1:\d+/", line)
            assert match, f"harap view printed no URL: {line!r}"
            url = match.group(0)
            status, body = fetch(url)
            assert status == 200 and mark in body.decode(), f"/: {status}, not the installed page"
            for asset in ("app.js", "vendor/three/build/three.module.js"):
                status, body = fetch(url + asset)
                assert status == 200 and body == (page / asset).read_bytes(), \
                    f"/{asset}: {status}, not the installed file"
            status, _ = fetch(url + "..%2F..%2Fbin/harap")
            assert status == 404, f"a path outside the page's files answered {status}"
        finally:
            server.send_signal(signal.SIGTERM)
            server.wait(timeout=30)
        assert server.returncode == 0, f"harap view exited with {server.returncode}"
    print("ok: the installed harap view serves its page from the install tree")


if __name__ == "__main__":
    main()
