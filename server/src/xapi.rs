//! Results to a Learning Record Store (LRS): xAPI 1.0.3 statements for every finished
//! exercise attempt (docs/xapi.md).
//!
//! * **Queue.** The recorder adds a finished attempt (`passed` or `failed`, a named trainee)
//!   to the database's outbox in the same transaction that stores its result
//!   ([`crate::db::Write::XapiQueue`]), so only stored results are sent, the queue survives a
//!   restart, and nothing on a session's path waits for the LRS. The outbox is bounded
//!   ([`crate::db::OUTBOX_CAPACITY`] rows).
//! * **Statements** ([`statements`]) are built from the stored attempt: `attempted`,
//!   `completed` (when every step was done), `passed` or `failed`, and `scored`, with the
//!   trainee as an `account` agent and the exercise as an activity. Their ids are name-based
//!   UUIDs of the attempt and the verb ([`statement_id`]), so a retry after a lost answer
//!   sends the same statements again, which the LRS takes as the ones it has (xAPI 1.0.3
//!   part 3 §2.1.1: an LRS makes no change for an id it already has, answering 204 or 409).
//! * **Sender** ([`send_loop`]): a background task that claims due outbox rows, posts each
//!   attempt's statements in one request (HTTP Basic with the configured credentials), and
//!   on failure tries again with exponential back-off ([`backoff_s`]). `/metrics` counts the
//!   statements sent, the attempts pending, the failed tries and the refused attempts.

use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Duration;

use anyhow::{Result, anyhow};
use serde_json::{Map, Value, json};
use sha1::{Digest, Sha1};

use crate::db::{Db, XapiSource};
use crate::metrics::Metrics;

/// The xAPI version sent in `X-Experience-API-Version`.
pub const VERSION: &str = "1.0.3";
/// ADL verb: the trainee started the exercise.
pub const ATTEMPTED: &str = "http://adlnet.gov/expapi/verbs/attempted";
/// ADL verb: every step of the exercise done.
pub const COMPLETED: &str = "http://adlnet.gov/expapi/verbs/completed";
/// ADL verb: passed.
pub const PASSED: &str = "http://adlnet.gov/expapi/verbs/passed";
/// ADL verb: failed.
pub const FAILED: &str = "http://adlnet.gov/expapi/verbs/failed";
/// ADL verb: the attempt's score.
pub const SCORED: &str = "http://adlnet.gov/expapi/verbs/scored";
/// The namespace of the statement ids: RFC 4122 Appendix C's URL namespace
/// (`6ba7b811-9dad-11d1-80b4-00c04fd430c8`).
pub const NAMESPACE_URL: [u8; 16] = [
    0x6b, 0xa7, 0xb8, 0x11, 0x9d, 0xad, 0x11, 0xd1, 0x80, 0xb4, 0x00, 0xc0, 0x4f, 0xd4, 0x30, 0xc8,
];
/// How often the sender looks for due rows.
pub const POLL: Duration = Duration::from_secs(1);
/// Attempts sent per look.
pub const BATCH: usize = 20;
/// How long a claimed row is left to its sender before another may take it (s).
pub const LEASE_S: f64 = 60.0;
/// The first retry's delay (s); each further one doubles, up to [`MAX_BACKOFF_S`].
pub const FIRST_BACKOFF_S: f64 = 1.0;
/// The longest delay between two tries of one attempt (s).
pub const MAX_BACKOFF_S: f64 = 60.0;
/// Timeout of one request to the LRS.
pub const REQUEST_TIMEOUT: Duration = Duration::from_secs(10);

/// Where and how to send (from `--xapi-endpoint` and the `SEAARMS_XAPI_*` environment).
#[derive(Clone)]
pub struct XapiConfig {
    /// The LRS's xAPI base URL, without a trailing `/` (statements go to
    /// `<endpoint>/statements`).
    pub endpoint: String,
    /// HTTP Basic user name and password, when set.
    pub credentials: Option<(String, String)>,
    /// The server's public URL without a trailing `/`: the trainees' account home page, the
    /// exercises' activity ids and our extensions' IRIs start with it (empty until
    /// [`XapiConfig::or_listening_on`] fills it when `--public-url` is not set).
    pub public_url: String,
}

impl std::fmt::Debug for XapiConfig {
    // The password never appears in a log or an error.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("XapiConfig")
            .field("endpoint", &self.endpoint)
            .field("user", &self.credentials.as_ref().map(|(u, _)| u))
            .field("public_url", &self.public_url)
            .finish()
    }
}

impl XapiConfig {
    /// Checks the endpoint (an `http://` or `https://` URL) and the credentials (both or
    /// neither).
    pub fn new(
        endpoint: &str,
        username: Option<&str>,
        password: Option<&str>,
        public_url: &str,
    ) -> Result<XapiConfig> {
        let endpoint = endpoint.trim_end_matches('/');
        let parsed = reqwest::Url::parse(endpoint)
            .map_err(|e| anyhow!("--xapi-endpoint `{endpoint}` is not a URL: {e}"))?;
        anyhow::ensure!(
            matches!(parsed.scheme(), "http" | "https") && parsed.host().is_some(),
            "--xapi-endpoint must be an http:// or https:// URL, got `{endpoint}`"
        );
        anyhow::ensure!(
            parsed.password().is_none(),
            "--xapi-endpoint must not carry a password; set SEAARMS_XAPI_USERNAME and \
             SEAARMS_XAPI_PASSWORD"
        );
        let credentials = match (username.filter(|u| !u.is_empty()), password) {
            (Some(u), Some(p)) => Some((u.to_string(), p.to_string())),
            (None, None) => None,
            _ => anyhow::bail!(
                "set both SEAARMS_XAPI_USERNAME and SEAARMS_XAPI_PASSWORD, or neither"
            ),
        };
        Ok(XapiConfig {
            endpoint: endpoint.to_string(),
            credentials,
            public_url: public_url.trim_end_matches('/').to_string(),
        })
    }

    /// With `http://<addr>` as the public URL when none was configured.
    pub fn or_listening_on(mut self, addr: std::net::SocketAddr) -> XapiConfig {
        if self.public_url.is_empty() {
            self.public_url = format!("http://{addr}");
        }
        self
    }

    /// The IRI of our result extension holding the attempt's metrics.
    pub fn metrics_iri(&self) -> String {
        format!("{}/xapi/extensions/metrics", self.public_url)
    }

    /// The IRI of our context extension holding the attempt's and session's ids.
    pub fn attempt_iri(&self) -> String {
        format!("{}/xapi/extensions/attempt", self.public_url)
    }
}

/// A name-based UUID, version 5 (SHA-1; RFC 4122 §4.3): the first 16 bytes of
/// SHA-1(namespace ‖ name), with the version (5) and the variant (RFC 4122) bits set.
pub fn uuid_v5(namespace: &[u8; 16], name: &[u8]) -> String {
    let mut h = Sha1::new();
    h.update(namespace);
    h.update(name);
    let d = h.finalize();
    let mut b = [0u8; 16];
    b.copy_from_slice(&d[..16]);
    b[6] = (b[6] & 0x0f) | 0x50;
    b[8] = (b[8] & 0x3f) | 0x80;
    let hex: String = b.iter().map(|x| format!("{x:02x}")).collect();
    format!(
        "{}-{}-{}-{}-{}",
        &hex[0..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..32]
    )
}

/// The id of attempt `attempt`'s statement with verb IRI `verb`: the same for every try.
pub fn statement_id(attempt: &str, verb: &str) -> String {
    uuid_v5(
        &NAMESPACE_URL,
        format!("urn:seaarms:attempt:{attempt}:{verb}").as_bytes(),
    )
}

/// The attempt's registration (xAPI `context.registration`): one UUID shared by its
/// statements.
pub fn registration(attempt: &str) -> String {
    uuid_v5(
        &NAMESPACE_URL,
        format!("urn:seaarms:attempt:{attempt}").as_bytes(),
    )
}

/// Unix seconds as an ISO 8601 UTC timestamp with milliseconds (`2001-09-09T01:46:40.000Z`;
/// the calendar fields of [`crate::api::results::utc_fields`]); a non-finite time is the epoch.
pub fn timestamp(unix: f64) -> String {
    let unix = if unix.is_finite() { unix } else { 0.0 };
    let [year, month, day, h, m, s, ms] = crate::api::results::utc_fields(unix);
    format!("{year:04}-{month:02}-{day:02}T{h:02}:{m:02}:{s:02}.{ms:03}Z")
}

/// Seconds as an ISO 8601 duration to 0.01 s, as xAPI keeps them (`PT83.25S`; xAPI 1.0.3
/// part 2 §4.6).
pub fn duration(seconds: f64) -> String {
    let s = if seconds.is_finite() {
        seconds.max(0.0)
    } else {
        0.0
    };
    format!("PT{s:.2}S")
}

fn verb(id: &str) -> Value {
    let word = id.rsplit('/').next().unwrap_or(id);
    json!({"id": id, "display": {"en-US": word}})
}

/// The attempt's metrics from its stored assessment: every field of
/// [`seaarms_core::exercise::Metrics`] the assessment holds (its names, its units).
fn metrics_of(assessment: Option<&Value>) -> Map<String, Value> {
    let names = serde_json::to_value(seaarms_core::exercise::Metrics::default())
        .ok()
        .and_then(|v| v.as_object().map(|m| m.keys().cloned().collect::<Vec<_>>()))
        .unwrap_or_default();
    let mut out = Map::new();
    if let Some(a) = assessment.and_then(Value::as_object) {
        for name in names {
            if let Some(v) = a.get(&name) {
                out.insert(name, v.clone());
            }
        }
    }
    out
}

/// The statements of a finished exercise attempt, in the order sent: `attempted` (at its
/// start), `completed` (when every step was done), `passed` or `failed`, and `scored` (at its
/// end). Built only from the stored attempt, the trainee's id and the exercise file (for
/// the activity's name and description), so a retry builds the very same statements.
/// Empty for an attempt that is not a finished exercise attempt.
pub fn statements(
    src: &XapiSource,
    exercise: Option<&seaarms_core::exercise::ExerciseSpec>,
    config: &XapiConfig,
) -> Vec<Value> {
    let a = &src.attempt;
    let (Some(exercise_id), Some(outcome)) = (a.exercise.as_deref(), a.outcome.as_deref()) else {
        return Vec::new();
    };
    let passed = match outcome {
        "passed" => true,
        "failed" => false,
        _ => return Vec::new(),
    };
    let score = a.score.filter(|s| s.is_finite()).unwrap_or(0.0);
    let completed = a
        .assessment
        .as_ref()
        .and_then(|v| v["completed"].as_bool())
        .unwrap_or(false);
    let mut actor = json!({
        "objectType": "Agent",
        "account": {"homePage": config.public_url, "name": src.trainee_id},
    });
    let name = crate::names::display_name(&a.trainee);
    if !name.is_empty() {
        actor["name"] = json!(name);
    }
    let mut definition = json!({
        "type": "http://adlnet.gov/expapi/activities/simulation",
    });
    match exercise {
        Some(e) => {
            definition["name"] = json!({"en-US": e.title});
            definition["description"] = json!({"en-US": e.goal});
        }
        None => definition["name"] = json!({"en-US": exercise_id}),
    }
    let object = json!({
        "objectType": "Activity",
        "id": format!("{}/exercises/{exercise_id}", config.public_url),
        "definition": definition,
    });
    let context = json!({
        "registration": registration(&a.id),
        "platform": "seaarms",
        "extensions": {config.attempt_iri(): {
            "attempt": a.id,
            "session": a.session,
            "exercise_version": a.exercise_version,
            "sim_version": a.sim_version,
            "group": a.group,
        }},
    });
    let ended = a.ended_unix.unwrap_or(a.started_unix);
    let score_json = json!({
        "scaled": (score / 100.0).clamp(0.0, 1.0),
        "raw": score.clamp(0.0, 100.0),
        "min": 0,
        "max": 100,
    });
    let statement = |verb_id: &str, unix: f64, result: Option<Value>| {
        let mut s = json!({
            "id": statement_id(&a.id, verb_id),
            "actor": actor,
            "verb": verb(verb_id),
            "object": object,
            "context": context,
            "timestamp": timestamp(unix),
        });
        if let Some(r) = result {
            s["result"] = r;
        }
        s
    };
    let mut out = vec![statement(ATTEMPTED, a.started_unix, None)];
    if completed {
        out.push(statement(
            COMPLETED,
            ended,
            Some(json!({"completion": true, "duration": duration(a.sim_seconds)})),
        ));
    }
    out.push(statement(
        if passed { PASSED } else { FAILED },
        ended,
        Some(json!({
            "score": score_json,
            "success": passed,
            "completion": completed,
            "duration": duration(a.sim_seconds),
            "extensions": {config.metrics_iri(): metrics_of(a.assessment.as_ref())},
        })),
    ));
    out.push(statement(SCORED, ended, Some(json!({"score": score_json}))));
    out
}

/// The delay before the next try of a row that has failed `tries` times before this one:
/// [`FIRST_BACKOFF_S`] · 2^tries, at most [`MAX_BACKOFF_S`].
pub fn backoff_s(tries: i64) -> f64 {
    let n = i32::try_from(tries.clamp(0, 30)).unwrap_or(30);
    (FIRST_BACKOFF_S * 2f64.powi(n)).min(MAX_BACKOFF_S)
}

/// What the LRS made of one attempt's statements.
enum Sent {
    /// Stored (200), or already there (204).
    Accepted,
    /// Refused for good: the statements are malformed (400) or differ from ones it holds
    /// under the same ids (409); trying again would not help.
    Refused(String),
    /// Not now (the LRS is down or overloaded, or answered anything else): try again later.
    Failed(String),
}

async fn post(http: &reqwest::Client, config: &XapiConfig, statements: &[Value]) -> Sent {
    let mut req = http
        .post(format!("{}/statements", config.endpoint))
        .header("X-Experience-API-Version", VERSION)
        .json(statements);
    if let Some((user, password)) = &config.credentials {
        req = req.basic_auth(user, Some(password));
    }
    match req.send().await {
        Ok(r) => {
            let status = r.status();
            if status.is_success() {
                return Sent::Accepted;
            }
            let mut body = r.text().await.unwrap_or_default();
            body.truncate(300);
            let why = format!("{status}: {body}");
            match status.as_u16() {
                400 | 409 => Sent::Refused(why),
                _ => Sent::Failed(why),
            }
        }
        // reqwest's error names the URL, not the credentials.
        Err(e) => Sent::Failed(format!("{e}")),
    }
}

/// Sends one claimed attempt's statements and records what came of it; `Ok(false)` when
/// the LRS did not take them now (down, erring), so the rest of the batch waits.
async fn send_one(
    db: &Db,
    metrics: &Metrics,
    http: &reqwest::Client,
    config: &XapiConfig,
    attempt: &str,
    tries: i64,
) -> Result<bool> {
    let Some(src) = db.xapi_source(attempt).await? else {
        // Deleted by retention meanwhile, or no trainee: nothing to send.
        db.xapi_done(attempt).await?;
        return Ok(true);
    };
    let exercise = src
        .attempt
        .exercise
        .as_deref()
        .and_then(|id| crate::catalogue::EXERCISES.get(id));
    let statements = statements(&src, exercise.as_deref(), config);
    if statements.is_empty() {
        db.xapi_done(attempt).await?;
        return Ok(true);
    }
    match post(http, config, &statements).await {
        Sent::Accepted => {
            db.xapi_done(attempt).await?;
            metrics
                .xapi_statements_sent
                .fetch_add(statements.len() as u64, Ordering::Relaxed);
            tracing::debug!(%attempt, n = statements.len(), "xAPI statements sent");
        }
        Sent::Refused(why) => {
            tracing::error!(%attempt, "the LRS refused the attempt's xAPI statements: {why}");
            metrics.xapi_refused.fetch_add(1, Ordering::Relaxed);
            db.xapi_reject(attempt, &why).await?;
        }
        Sent::Failed(why) => {
            let delay = backoff_s(tries);
            if tries == 0 {
                tracing::warn!(%attempt, "sending xAPI statements failed (retrying): {why}");
            } else {
                tracing::debug!(%attempt, tries, "sending xAPI statements failed again: {why}");
            }
            metrics.xapi_send_failures.fetch_add(1, Ordering::Relaxed);
            db.xapi_retry(attempt, crate::clock::unix_now() + delay, &why)
                .await?;
            return Ok(false);
        }
    }
    Ok(true)
}

/// The sender: every [`POLL`], claims up to [`BATCH`] due outbox rows and sends them, one
/// request per attempt, in order, stopping at the first try the LRS fails (the rest wait
/// out their [`LEASE_S`]); keeps `seaarms_xapi_pending` current. Runs until aborted.
pub async fn send_loop(db: Db, metrics: Arc<Metrics>, config: Arc<XapiConfig>) {
    let http = match reqwest::Client::builder()
        .timeout(REQUEST_TIMEOUT)
        .user_agent(concat!("seaarms/", env!("CARGO_PKG_VERSION")))
        .build()
    {
        Ok(c) => c,
        Err(e) => {
            tracing::error!("xAPI: cannot build the HTTP client: {e}");
            return;
        }
    };
    tracing::info!(endpoint = %config.endpoint, "xAPI statements go to the LRS");
    let mut tick = tokio::time::interval(POLL);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tick.tick().await;
        let claimed = match db
            .xapi_claim(crate::clock::unix_now(), LEASE_S, BATCH)
            .await
        {
            Ok(c) => c,
            Err(e) => {
                tracing::warn!("xAPI outbox: {e:#}");
                continue;
            }
        };
        for (attempt, tries) in &claimed {
            match send_one(&db, &metrics, &http, &config, attempt, *tries).await {
                Ok(true) => {}
                // The LRS is down: the batch's other rows stay claimed and are due again
                // after the lease, not tried now one by one.
                Ok(false) => break,
                Err(e) => tracing::warn!(%attempt, "xAPI outbox: {e:#}"),
            }
        }
        if let Ok(n) = db.xapi_pending().await {
            metrics.xapi_pending.store(n, Ordering::Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn name_based_uuids_match_python_uuid5() {
        // Python's documentation of `uuid.uuid5(uuid.NAMESPACE_DNS, 'python.org')`:
        // 886313e1-3b8a-5372-9b90-0c9aee199e5d (NAMESPACE_DNS is RFC 4122's 6ba7b810-…).
        let mut dns = NAMESPACE_URL;
        dns[3] = 0x10;
        assert_eq!(
            uuid_v5(&dns, b"python.org"),
            "886313e1-3b8a-5372-9b90-0c9aee199e5d"
        );
        let a = statement_id("0123456789abcdef", PASSED);
        assert_eq!(a, statement_id("0123456789abcdef", PASSED), "deterministic");
        assert_ne!(a, statement_id("0123456789abcdef", SCORED));
        assert_ne!(a, statement_id("0123456789abcdee", PASSED));
    }

    #[test]
    fn timestamps_and_durations_are_iso_8601() {
        // 10⁹ s after the epoch: 2001-09-09 01:46:40 UTC (the "billennium").
        assert_eq!(timestamp(1e9), "2001-09-09T01:46:40.000Z");
        assert_eq!(timestamp(0.0), "1970-01-01T00:00:00.000Z");
        // 2000-02-29 (a leap day of a century leap year) is day 11016 after the epoch.
        assert_eq!(
            timestamp(11016.0 * 86400.0 + 0.25),
            "2000-02-29T00:00:00.250Z"
        );
        assert_eq!(duration(83.254), "PT83.25S");
        assert_eq!(duration(f64::NAN), "PT0.00S");
    }

    fn source(outcome: &str, completed: bool) -> XapiSource {
        XapiSource {
            attempt: crate::db::AttemptRow {
                id: "0123456789abcdef".into(),
                session: "fedcba9876543210".into(),
                trainee: "Ada Lovelace".into(),
                group: "A".into(),
                scenario: "familiarisation".into(),
                exercise: Some("familiarisation".into()),
                exercise_version: Some("1".into()),
                sim_version: "v".into(),
                started_unix: 1e9,
                ended_unix: Some(1e9 + 90.0),
                sim_seconds: 90.0,
                outcome: Some(outcome.into()),
                score: Some(42.0),
                assessment: Some(json!({"completed": completed, "time_s": 90.0, "exercise": "x"})),
                init: Value::Null,
                inputs_bytes: 0,
                practice: false,
                taken_over_from: None,
            },
            trainee_id: "00112233aabbccdd".into(),
        }
    }

    #[test]
    fn a_failed_attempt_is_attempted_failed_and_scored() {
        let config = XapiConfig::new("http://lrs/xAPI", None, None, "https://sim").unwrap();
        let st = statements(&source("failed", false), None, &config);
        let verbs: Vec<&str> = st.iter().filter_map(|s| s["verb"]["id"].as_str()).collect();
        assert_eq!(verbs, [ATTEMPTED, FAILED, SCORED], "no `completed`");
        let failed = &st[1];
        assert_eq!(failed["result"]["success"], false);
        assert_eq!(failed["result"]["completion"], false);
        assert_eq!(failed["result"]["score"]["scaled"], 0.42);
        assert_eq!(failed["result"]["duration"], "PT90.00S");
        assert_eq!(failed["timestamp"], "2001-09-09T01:48:10.000Z");
        assert_eq!(
            st[0]["timestamp"], "2001-09-09T01:46:40.000Z",
            "attempted at the start"
        );
        // Only the metrics ride along, not the assessment's other fields.
        let m = &failed["result"]["extensions"]["https://sim/xapi/extensions/metrics"];
        assert_eq!(m["time_s"], 90.0);
        assert!(m.get("exercise").is_none() && m.get("completed").is_none());
        assert_eq!(failed["actor"]["account"]["name"], "00112233aabbccdd");
        assert_eq!(
            failed["object"]["id"],
            "https://sim/exercises/familiarisation"
        );
        let passed = statements(&source("passed", true), None, &config);
        let verbs: Vec<&str> = passed
            .iter()
            .filter_map(|s| s["verb"]["id"].as_str())
            .collect();
        assert_eq!(verbs, [ATTEMPTED, COMPLETED, PASSED, SCORED]);
        assert!(statements(&source("abandoned", false), None, &config).is_empty());
    }

    #[test]
    fn backoff_doubles_up_to_its_cap() {
        assert_eq!(backoff_s(0), 1.0);
        assert_eq!(backoff_s(3), 8.0);
        assert_eq!(backoff_s(10), MAX_BACKOFF_S);
        assert_eq!(backoff_s(i64::MAX), MAX_BACKOFF_S);
    }

    #[test]
    fn credentials_come_in_pairs_and_never_show() {
        let c = XapiConfig::new(
            "https://lrs.example/xAPI/",
            Some("u"),
            Some("secret"),
            "https://sim/",
        )
        .unwrap();
        assert_eq!(c.endpoint, "https://lrs.example/xAPI");
        assert_eq!(c.public_url, "https://sim");
        assert!(!format!("{c:?}").contains("secret"));
        assert!(XapiConfig::new("https://lrs", Some("u"), None, "x").is_err());
        assert!(XapiConfig::new("ftp://lrs", None, None, "x").is_err());
        assert!(XapiConfig::new("https://u:p@lrs", None, None, "x").is_err());
    }
}
