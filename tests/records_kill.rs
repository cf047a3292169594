//! Durability under `kill -9`: the real binary records sessions driven over WebSockets, is
//! killed with SIGKILL, and the session index on disk still holds true figures (within 1 s
//! of the CSV's last row: the index gets a progress line after every write of the CSV);
//! the CSV holds only whole rows; a restarted server lists the sessions as interrupted with
//! those figures.

#![allow(clippy::unwrap_used)]

mod common;
mod records_common;

use std::time::Duration;

use common::{create_at, get_json, get_text};
use records_common::{Binary, Csv, drive, temp_dir};
use serde_json::json;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kill_9_leaves_true_figures_and_whole_rows() {
    let dir = temp_dir("kill9");
    let keep_all = ["--retention-days", "0", "--retention-max-mb", "0"];
    let server = Binary::start(&dir, &keep_all);
    let mut sessions = Vec::new();
    for (label, scenario) in [("a", "training"), ("b", "case4-dual-closed-loop")] {
        let (st, c) = create_at(&server.base, json!({"label": label, "scenario": scenario})).await;
        assert_eq!(st, 201, "{c}");
        sessions.push(c);
    }
    // Drive both for three seconds at once (shoulders full down, into the seabed / limit),
    // then let the recorder write once more.
    tokio::join!(drive(&sessions[0], 0, 3.0), drive(&sessions[1], 0, 3.0));
    tokio::time::sleep(Duration::from_millis(1200)).await;
    server.kill9();

    let index = seaarms::sessions::record::read_index(&dir.join("sessions.jsonl"));
    let mut figures = Vec::new();
    for c in &sessions {
        let id = c["id"].as_str().unwrap();
        let rec = index
            .iter()
            .find(|r| r.id == id)
            .unwrap_or_else(|| panic!("{id} not in the index"));
        assert_eq!(rec.ended_unix, None, "killed: no end line");
        let csv_path = dir.join("sessions").join(format!("{id}.csv"));
        let csv = Csv::read(&csv_path);
        if csv.cut_tail > 0 {
            eprintln!(
                "{id}: the kill landed inside a write: {} bytes of a row after the last whole \
                 row (readers skip them; start-up cuts them)",
                csv.cut_tail
            );
        }
        let t_csv = csv.last("t");
        let relief_csv = csv.last("relief_events") as u64;
        let t_index = rec.sim_seconds.expect("progress figures in the index");
        let overloads_index = rec.overloads.expect("overloads in the index");
        eprintln!(
            "{id}: CSV {} rows, last t {t_csv} s, relief {relief_csv}; index {t_index} s, \
             overloads {overloads_index}",
            csv.rows.len()
        );
        // Over 1.5 s of the ~4 s run on disk (a loaded machine may drop steps).
        assert!(
            t_csv > 1.5,
            "{id}: ~4 s of running recorded only to {t_csv} s"
        );
        assert!(
            (t_csv - t_index).abs() <= 1.0,
            "{id}: index {t_index} s vs CSV {t_csv} s"
        );
        // The index describes rows already on disk, so it is never ahead of the CSV, and
        // with no reset the session's overloads equal the simulation's relief counter.
        assert!(t_index <= t_csv);
        assert!(overloads_index <= relief_csv);
        if t_index == t_csv {
            assert_eq!(overloads_index, relief_csv);
        }
        figures.push((id.to_string(), t_index, overloads_index, t_csv, csv_path));
    }

    // A new server on the same data: both sessions interrupted, with the indexed figures;
    // their CSVs end with a whole row.
    let server = Binary::start(&dir, &keep_all);
    let list = get_json(&format!("{}/api/sessions", server.base)).await;
    for (id, t_index, overloads_index, t_csv, csv_path) in &figures {
        let entry = list
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["id"] == id.as_str())
            .unwrap_or_else(|| panic!("{id} not listed: {list}"));
        assert_eq!(entry["status"], "ended");
        assert_eq!(entry["end_reason"], "interrupted (server stopped)");
        assert_eq!(entry["sim_seconds"].as_f64().unwrap(), *t_index);
        assert_eq!(entry["overload_count"].as_u64().unwrap(), *overloads_index);
        assert_eq!(entry["recording"], "ok");
        let bytes = std::fs::read(csv_path).unwrap();
        assert_eq!(
            bytes.last(),
            Some(&b'\n'),
            "{id}: CSV ends mid-row after restart"
        );
        let download = get_text(&format!("{}/api/sessions/{id}/log.csv", server.base)).await;
        let mut r = csv::Reader::from_reader(download.as_bytes());
        let width = r.headers().unwrap().len();
        let mut last_t = 0.0;
        for rec in r.records() {
            let rec = rec.unwrap();
            assert_eq!(rec.len(), width);
            last_t = rec[0].parse().unwrap();
        }
        assert_eq!(last_t, *t_csv);
    }
    server.kill9();
    let _ = std::fs::remove_dir_all(&dir);
}
