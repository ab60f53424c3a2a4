# SPDX-License-Identifier: MIT
"""harap.view and Session.view: the page of `harap view` served from Python on a free port,
fetched with urllib, then stopped; bad arguments raise harap errors naming them."""
import urllib.error
import urllib.request

import numpy as np
import pytest

import harap


def fetch(url):
    with urllib.request.urlopen(url, timeout=30) as response:
        return response.status, response.read().decode()


def test_view_serves_the_page_until_stopped(cylinder):
    V, F, handles, targets = cylinder
    with harap.view(V, F, handles, targets, port=0) as page:
        assert page.running and page.port > 0
        assert page.url == f"http://127.0.0.1:{page.port}/"
        status, body = fetch(page.url)
        assert status == 200 and "<title>harap view</title>" in body
        status, script = fetch(page.url + "app.js")
        assert status == 200 and "WebSocket" in script
        with pytest.raises(urllib.error.HTTPError) as missing:
            fetch(page.url + "../CMakeCache.txt")
        assert missing.value.code == 404
    assert not page.running
    with pytest.raises(urllib.error.URLError):
        fetch(page.url)


def test_session_view_and_handle_groups(cylinder):
    V, F, handles, targets = cylinder
    session = harap.Session(V, F, options={"optimizer.tolerance": 1e-6})
    session.set_handles(handles, targets)
    page = session.view(port=0)
    try:
        assert fetch(page.url)[0] == 200
    finally:
        page.stop()
    bottom, top = handles[V[handles, 2] < 2], handles[V[handles, 2] > 2]
    with harap.view(V, F, [bottom, top], port=0) as groups:
        assert fetch(groups.url)[0] == 200


def test_view_with_soft_handles(cylinder):
    """Soft handles (weights) reach the page's session: one weight per dragged group."""
    V, F, handles, targets = cylinder
    weights = np.where(V[handles, 2] > 2, 5.0, np.inf)
    session = harap.Session(V, F, options={"optimizer.tolerance": 1e-6})
    session.set_handles(handles, targets, weights=weights)
    with session.view(port=0) as page:
        assert fetch(page.url)[0] == 200
    bottom, top = handles[V[handles, 2] < 2], handles[V[handles, 2] > 2]
    with harap.view(V, F, [bottom, top], weights=np.r_[np.full(len(bottom), np.inf),
                                                       np.full(len(top), 5.0)], port=0) as page:
        assert fetch(page.url)[0] == 200
    mixed = np.r_[np.full(len(bottom), np.inf), np.full(len(top) - 1, 5.0), 2.0]
    with pytest.raises(harap.InputError, match="handle group 2 mixes weights"):
        harap.view(V, F, [bottom, top], weights=mixed, port=0)
    with pytest.raises(harap.InputError, match="weight of handle vertex"):
        harap.view(V, F, handles, weights=np.full(len(handles), -1.0), port=0)
    with pytest.raises(harap.InputError, match="one per handle"):
        harap.view(V, F, handles, weights=np.ones(2), port=0)


def test_view_bad_arguments(cylinder):
    V, F, handles, targets = cylinder
    with pytest.raises(harap.InputError, match="port must be in 0..65535"):
        harap.view(V, F, port=70000)
    with pytest.raises(harap.ConfigError, match="port must be an integer"):
        harap.view(V, F, port="80")
    with pytest.raises(harap.InputError, match="handles: indices"):
        harap.view(V, F, np.array([len(V)]))
    with pytest.raises(harap.InputError, match="display_vertices"):
        harap.view(V, F, port=0, display_vertices=2)
    with pytest.raises(harap.InputError, match="not an IP address"):
        harap.view(V, F, port=0, host="nowhere")
