// Live progress for the campaign list and the campaign page: polls the JSON API (same origin, the login cookie).
"use strict";

const FINAL = ["done", "failed", "cancelled"];

function failuresText(failures) {
  const parts = Object.entries(failures).map(([status, n]) => `${status} ${n}`);
  return parts.length ? parts.join(" ") : "none";
}

function show(root, c) {
  const p = c.progress;
  const field = (name) => root.querySelector(`[data-field="${name}"]`);
  const state = field("state");
  if (state) { state.textContent = c.state; state.className = `state ${c.state}`; }
  const stage = field("stage");
  if (stage) stage.textContent = c.state === "running" ? `${c.stage}${c.stage_message ? ": " + c.stage_message : ""}` : "";
  const bar = field("bar");
  if (bar) { bar.max = p.runs_total; bar.value = p.runs_done; }
  const runs = field("runs");
  if (runs) runs.textContent = `${p.runs_done} / ${p.runs_total} runs (${p.percent.toFixed(1)} %)`;
  const running = field("running");
  if (running && c.timings.running_seconds !== null) running.textContent = c.timings.running_seconds.toFixed(1);
  const failures = field("failures");
  if (failures) failures.textContent = failuresText(p.failures);
}

async function poll(url) {
  const response = await fetch(url, { credentials: "same-origin", cache: "no-store" });
  if (!response.ok) throw new Error(`${url}: ${response.status}`);
  return response.json();
}

function watchCampaign(section) {
  const id = section.dataset.pollCampaign;
  if (FINAL.includes(section.dataset.state)) return;
  const tick = async () => {
    try {
      const c = await poll(`/api/v1/campaigns/${id}`);
      show(section, c);
      if (FINAL.includes(c.state)) { window.location.reload(); return; }  // verdicts, files: rendered by the server
    } catch (error) { console.warn(error); }
    setTimeout(tick, 1500);
  };
  setTimeout(tick, 1500);
}

function watchList(table) {
  const tick = async () => {
    try {
      const { campaigns } = await poll("/api/v1/campaigns");
      for (const c of campaigns) {
        const row = table.querySelector(`tr[data-id="${c.id}"]`);
        if (row) show(row, c);
      }
      if (campaigns.some((c) => !table.querySelector(`tr[data-id="${c.id}"]`))) { window.location.reload(); return; }
    } catch (error) { console.warn(error); }
    setTimeout(tick, 2000);
  };
  setTimeout(tick, 2000);
}

document.addEventListener("DOMContentLoaded", () => {
  const section = document.querySelector("[data-poll-campaign]");
  if (section) watchCampaign(section);
  const table = document.querySelector("[data-poll-list]");
  if (table) watchList(table);
});
