"""The two pages: the token's log-in, and the console (textual-serve's terminal script, with the
E-STOP button above it). Everything shown that comes from outside is escaped."""

from __future__ import annotations

from html import escape

_STYLE = """
html, body { margin: 0; height: 100%; overflow: hidden; }
body { background: #0c181f; color: #e8eef2; font-family: sans-serif; display: flex;
  flex-direction: column; }
header { display: flex; align-items: center; gap: 16px; padding: 6px 12px; background: #12232d;
  height: 44px; box-sizing: border-box; flex: none; }
header .robot { flex: 1; font-family: monospace; font-size: 15px; }
#estop { background: #c8102e; color: #fff; border: 3px solid #fff; border-radius: 6px;
  font-weight: bold; font-size: 18px; padding: 4px 22px; cursor: pointer; }
#estop:active { background: #8b0000; }
#latch { font-family: monospace; font-size: 15px; }
#latch.engaged { background: #c8102e; color: #fff; padding: 3px 8px; border-radius: 4px; }
#bell { font-family: monospace; font-size: 14px; position: relative; }
#bell summary { cursor: pointer; list-style: none; padding: 3px 8px; border-radius: 4px; }
#bell.open summary { background: #b36b00; color: #fff; }
#bell.new summary { outline: 3px solid #ffd24d; }
#bell ul { position: absolute; right: 0; top: 30px; z-index: 6; background: #12232d;
  margin: 0; padding: 8px 12px 8px 24px; width: 460px; border: 1px solid #3a5566; }
#terminal { flex: 1; min-height: 0; overflow: hidden; }
#ended { display: none; position: absolute; bottom: 0; left: 0; right: 0; padding: 24px;
  text-align: center; background: #0c181f; font-size: 18px; z-index: 5; }
body.-closed #ended { display: block; }
form { margin: 15vh auto; width: 420px; display: flex; flex-direction: column; gap: 12px; }
input { font-size: 16px; padding: 8px; }
button { font-size: 16px; padding: 8px; }
.wrong { color: #ff8080; }
"""


def login_page(robot: str, wrong: bool) -> str:
    said = '<p class="wrong">Wrong token: nothing was started.</p>' if wrong else ""
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><meta name="viewport" content="width=device-width">
<title>astiop: log in ({escape(robot)})</title><style>{_STYLE}</style></head>
<body><form method="post" action="login">
<h2>astiop: {escape(robot)}</h2>
<label for="token">The server's token</label>
<input id="token" name="token" type="password" autocomplete="current-password" autofocus>
<button type="submit">Open the console</button>{said}
</form></body></html>"""


# ctrl+e outside the terminal (the button focused, the page's margin) still stops the robot;
# inside it, the console's own ctrl+e does. Leaving the page ends its console: asked first.
_SCRIPT = """
// the console's websocket beside this page, whatever host, scheme or path a proxy put it on
const terminal = document.getElementById("terminal");
terminal.dataset.sessionWebsocketUrl = (location.protocol === "https:" ? "wss://" : "ws://") +
  location.host + location.pathname.replace(/[^/]*$/, "") + "ws";
const latch = document.getElementById("latch");
async function estop() {
  latch.textContent = "E-STOP: sending…";
  try {
    const r = await fetch("estop", {method: "POST", headers: {"X-Astiop": "estop"}});
    const body = await r.json();
    latch.textContent = body.message;
  } catch (e) { latch.textContent = "E-STOP: the server did not answer: " + e; }
  refresh();
}
async function refresh() {
  try {
    const r = await fetch("estop", {cache: "no-store"});
    const body = await r.json();
    latch.className = body.engaged ? "engaged" : "";
    if (!latch.textContent.startsWith("E-STOP: sending")) latch.textContent = body.message;
  } catch (e) { latch.className = ""; latch.textContent = "server unreachable"; }
}
document.getElementById("estop").addEventListener("click", estop);
window.addEventListener("keydown", (e) => {
  const inTerminal = e.target.closest && e.target.closest("#terminal");
  if (!inTerminal && e.ctrlKey && e.key.toLowerCase() === "e") { e.preventDefault(); estop(); }
  if (!inTerminal && e.ctrlKey && e.key.toLowerCase() === "r") { e.preventDefault(); }
}, true);
window.addEventListener("beforeunload", (e) => {
  if (!document.body.classList.contains("-closed")) { e.preventDefault(); e.returnValue = ""; }
});
// the bell: open alerts, no sound; a new one is outlined and counted in the tab's title
const bell = document.getElementById("bell");
let seen = -1;
async function ring() {
  try {
    const r = await fetch("alerts", {cache: "no-store"});
    const body = await r.json();
    bell.querySelector("summary").textContent = "alerts: " + body.open + " open";
    bell.classList.toggle("open", body.open > 0);
    if (seen >= 0 && body.newest > seen) bell.classList.add("new");
    if (body.open === 0) bell.classList.remove("new");
    seen = body.newest;
    const list = bell.querySelector("ul");
    list.replaceChildren(...body.alerts.map((text) => {
      const li = document.createElement("li"); li.textContent = text; return li; }));
    if (body.open > body.alerts.length) {
      const li = document.createElement("li");
      li.textContent = "… and " + (body.open - body.alerts.length) + " more: F8 in the console";
      list.append(li);
    }
    document.title = (body.open ? "(" + body.open + ") " : "") + baseTitle;
  } catch (e) { bell.querySelector("summary").textContent = "alerts: ?"; }
}
const baseTitle = document.title;
// opened, the new alerts are seen: cleared on the click itself ("toggle" comes a task later)
bell.querySelector("summary").addEventListener("click", () => bell.classList.remove("new"));
bell.addEventListener("toggle", () => bell.classList.remove("new"));
refresh();
ring();
setInterval(refresh, 1000);
setInterval(ring, 500);
"""


def console_page(robot: str, static_url: str, font_size: int) -> str:
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><meta name="viewport" content="width=device-width">
<title>astiop: {escape(robot)}</title>
<link rel="stylesheet" href="{escape(static_url)}css/xterm.css">
<script src="{escape(static_url)}js/textual.js"></script>
<style>{_STYLE}</style></head>
<body>
<header><span class="robot">astiop · robot: {escape(robot)}</span>
<details id="bell" title="Open alerts (acknowledged on the Alerts screen, F8)">
<summary>alerts</summary><ul></ul></details>
<span id="latch"></span>
<button id="estop" type="button" title="Stop the robot and latch the E-STOP (ctrl+e)">E-STOP</button>
</header>
<div id="ended">This console has ended. Reload the page to open a new one.</div>
<div id="terminal" class="textual-terminal" data-font-size="{font_size}"></div>
<script>{_SCRIPT}</script>
</body></html>"""
