//! A resynchronising reader of LSP base-protocol messages.
//!
//! tower-lsp-server's transport stops reading (and the server exits) after
//! the first message its codec cannot decode: a header without a
//! `Content-Length`, a body that is not JSON, garbage between messages. A
//! `Content-Length` larger than the body makes it wait for bytes that never
//! come. So the server reads its input through [`Framer`], which hands the
//! transport only well-framed JSON-RPC messages:
//!
//! * bytes before a `Content-Length:` header are skipped (and logged);
//! * a body that is JSON-RPC when cut at `Content-Length` is taken as is;
//! * otherwise (a length that is not a number, too large, too small or too
//!   large for the body) the first JSON value after the header is taken when
//!   it is complete and followed by nothing, whitespace or the next header;
//! * anything else is logged and skipped up to the next `Content-Length:`.
//!
//! The framer is sans-IO (`push` bytes, `next` messages); [`resync`] drives
//! it on an async reader.

/// Largest message accepted by its length (a larger `Content-Length` is
/// treated as wrong: the JSON value that follows is used instead).
pub const MAX_MESSAGE: usize = 256 << 20;

/// A header block longer than this without its blank line is garbage.
const MAX_HEADER: usize = 8 << 10;

const HEADER_NAME: &[u8] = b"content-length";

/// Splits a byte stream into JSON-RPC message bodies.
#[derive(Default)]
pub struct Framer {
    buf: Vec<u8>,
}

fn find_ci(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if hay.len() < needle.len() {
        return None;
    }
    (0..=hay.len() - needle.len()).find(|&i| hay[i..i + needle.len()].eq_ignore_ascii_case(needle))
}

fn is_jsonrpc(body: &[u8]) -> bool {
    use tower_lsp_server::jsonrpc::{Request, Response};
    serde_json::from_slice::<Request>(body).is_ok() || serde_json::from_slice::<Response>(body).is_ok()
}

/// The end of the header block starting at 0 (after its blank line), if complete.
fn header_end(buf: &[u8]) -> Option<usize> {
    let mut i = 0;
    while i < buf.len() {
        if buf[i] == b'\n' {
            // A line end followed by an empty line (`\r\n` or `\n`).
            let rest = &buf[i + 1..];
            if rest.starts_with(b"\r\n") {
                return Some(i + 3);
            }
            if rest.starts_with(b"\n") {
                return Some(i + 2);
            }
        }
        i += 1;
    }
    None
}

/// The value of the `Content-Length` header (the block starts with it).
fn content_length(header: &[u8]) -> Option<usize> {
    let text = std::str::from_utf8(header).ok()?;
    let line = text.lines().next()?;
    let (_, value) = line.split_once(':')?;
    value.trim().parse().ok()
}

enum Value {
    /// A complete JSON value of this many bytes.
    Complete(usize),
    /// The bytes are the beginning of a JSON value.
    Incomplete,
    /// Not JSON.
    Invalid,
}

fn first_json_value(bytes: &[u8]) -> Value {
    let mut it = serde_json::Deserializer::from_slice(bytes).into_iter::<serde_json::Value>();
    match it.next() {
        Some(Ok(_)) => Value::Complete(it.byte_offset()),
        Some(Err(e)) if e.is_eof() => Value::Incomplete,
        None => Value::Incomplete,
        Some(Err(_)) => Value::Invalid,
    }
}

impl Framer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends bytes read from the client.
    pub fn push(&mut self, data: &[u8]) {
        self.buf.extend_from_slice(data);
    }

    /// Whether bytes of an unfinished message are waiting.
    pub fn waiting(&self) -> bool {
        self.buf.iter().any(|b| !b.is_ascii_whitespace())
    }

    /// The next complete message body, if any. `stalled`: no more bytes are
    /// coming for now (the input paused or ended), so a complete JSON value
    /// shorter than its `Content-Length` is taken. `log` receives one line
    /// per thing skipped.
    pub fn next(&mut self, stalled: bool, log: &mut dyn FnMut(String)) -> Option<Vec<u8>> {
        loop {
            // 1. Find a header.
            let Some(p) = find_ci(&self.buf, HEADER_NAME) else {
                let keep = HEADER_NAME.len() - 1;
                if self.buf.len() > keep {
                    let cut = self.buf.len() - keep;
                    self.skip(cut, log);
                }
                return None;
            };
            if p > 0 {
                self.skip(p, log);
            }
            // 2. The whole header block.
            let Some(body_start) = header_end(&self.buf) else {
                if self.buf.len() > MAX_HEADER {
                    log("a header without its blank line; skipping it".into());
                    self.buf.drain(..1);
                    continue;
                }
                return None;
            };
            let declared = content_length(&self.buf[..body_start]);
            let body = &self.buf[body_start..];
            // 3. The usual case: the declared length frames a JSON-RPC message.
            if let Some(len) = declared.filter(|&l| l <= MAX_MESSAGE) {
                if body.len() >= len {
                    if is_jsonrpc(&body[..len]) {
                        let msg = body[..len].to_vec();
                        self.buf.drain(..body_start + len);
                        return Some(msg);
                    }
                } else if !stalled && find_ci(body, HEADER_NAME).is_none() {
                    return None; // keep reading
                }
            }
            // 4. The declared length is missing, wrong or too large: use the
            // JSON value that follows the header, if it is one.
            let what = match declared {
                None => "a Content-Length that is not a number".to_string(),
                Some(l) if l > MAX_MESSAGE => format!("a Content-Length of {l} bytes (too large)"),
                Some(l) => format!("a Content-Length of {l} bytes that does not frame a JSON-RPC message"),
            };
            match first_json_value(body) {
                Value::Complete(n) if is_jsonrpc(&body[..n]) => {
                    log(format!("{what}; using the {n}-byte JSON message after it"));
                    let msg = body[..n].to_vec();
                    self.buf.drain(..body_start + n);
                    return Some(msg);
                }
                // The rest of a value, or the body of a header that came alone.
                Value::Incomplete => return None,
                Value::Complete(_) | Value::Invalid => {
                    log(format!("{what}; skipping to the next header"));
                    self.buf.drain(..body_start);
                }
            }
        }
    }

    fn skip(&mut self, n: usize, log: &mut dyn FnMut(String)) {
        let garbage = self.buf[..n].iter().filter(|b| !b.is_ascii_whitespace()).count();
        if garbage > 0 {
            log(format!("skipping {n} bytes that are not a message header"));
        }
        self.buf.drain(..n);
    }
}

/// Re-frames `input` into a stream the transport can always decode (see the
/// module documentation); problems are logged on standard error.
pub fn resync<R>(input: R) -> tokio::io::DuplexStream
where
    R: tokio::io::AsyncRead + Unpin + Send + 'static,
{
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let (mut w, r) = tokio::io::duplex(1 << 16);
    tokio::spawn(async move {
        let mut input = input;
        let mut framer = Framer::new();
        let mut chunk = vec![0u8; 1 << 16];
        let mut log = |m: String| eprintln!("mcl-lsp: malformed input: {m}");
        // Whether the framer has seen the input pause since the last bytes.
        let mut stall_seen = false;
        loop {
            let n = if framer.waiting() && !stall_seen {
                match tokio::time::timeout(std::time::Duration::from_millis(100), input.read(&mut chunk)).await {
                    Ok(r) => r,
                    Err(_) => {
                        stall_seen = true;
                        while let Some(m) = framer.next(true, &mut log) {
                            if forward(&mut w, &m).await.is_err() {
                                return;
                            }
                        }
                        continue;
                    }
                }
            } else {
                input.read(&mut chunk).await
            };
            let n = match n {
                Ok(0) | Err(_) => {
                    while let Some(m) = framer.next(true, &mut log) {
                        if forward(&mut w, &m).await.is_err() {
                            return;
                        }
                    }
                    return;
                }
                Ok(n) => n,
            };
            stall_seen = false;
            framer.push(&chunk[..n]);
            while let Some(m) = framer.next(false, &mut log) {
                if forward(&mut w, &m).await.is_err() {
                    return;
                }
            }
        }
    });

    async fn forward(w: &mut tokio::io::DuplexStream, body: &[u8]) -> std::io::Result<()> {
        let header = format!("Content-Length: {}\r\n\r\n", body.len());
        w.write_all(header.as_bytes()).await?;
        w.write_all(body).await
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(id: u32) -> String {
        format!(r#"{{"jsonrpc":"2.0","id":{id},"method":"shutdown"}}"#)
    }

    fn framed(body: &str) -> String {
        format!("Content-Length: {}\r\n\r\n{body}", body.len())
    }

    /// Feeds `input` in pieces of `step` bytes; returns the messages and the log.
    fn run(input: &str, step: usize) -> (Vec<String>, Vec<String>) {
        let mut f = Framer::new();
        let mut out = Vec::new();
        let mut logs = Vec::new();
        for piece in input.as_bytes().chunks(step.max(1)) {
            f.push(piece);
            while let Some(m) = f.next(false, &mut |l| logs.push(l)) {
                out.push(String::from_utf8(m).unwrap());
            }
        }
        while let Some(m) = f.next(true, &mut |l| logs.push(l)) {
            out.push(String::from_utf8(m).unwrap());
        }
        (out, logs)
    }

    fn check(input: &str, want: &[u32], logged: bool) {
        for step in [1, 3, 7, 64, input.len()] {
            let (out, logs) = run(input, step);
            let want: Vec<String> = want.iter().map(|&i| msg(i)).collect();
            assert_eq!(out, want, "step {step}, input {input:?}, log {logs:?}");
            assert_eq!(!logs.is_empty(), logged, "step {step}: {logs:?}");
        }
    }

    #[test]
    fn well_framed_messages_pass_untouched() {
        check(&format!("{}{}", framed(&msg(1)), framed(&msg(2))), &[1, 2], false);
        let with_type = format!(
            "Content-Length: {}\r\nContent-Type: application/vscode-jsonrpc; charset=utf-8\r\n\r\n{}",
            msg(1).len(),
            msg(1)
        );
        check(&with_type, &[1], false);
    }

    #[test]
    fn garbage_between_messages_is_skipped() {
        check(&format!("{}garbage\r\n\u{1}\u{2}{}", framed(&msg(1)), framed(&msg(2))), &[1, 2], true);
        check(&format!("xxContent-Length{}", framed(&msg(1))), &[1], true);
    }

    #[test]
    fn bodies_that_are_not_json_rpc_are_skipped() {
        check(&format!("{}{}", framed("{ this is not json"), framed(&msg(2))), &[2], true);
        check(&format!("{}{}", framed("[1, 2, 3]"), framed(&msg(2))), &[2], true);
        check(&format!("{}{}", framed(r#"{"a": 1}"#), framed(&msg(2))), &[2], true);
    }

    #[test]
    fn wrong_lengths_use_the_json_value() {
        let m = msg(1);
        // Not a number, negative, too small, too large, huge.
        for len in
            ["abc".to_string(), "-3".into(), "10".into(), format!("{}", m.len() + 40), "99999999999999999".into()]
        {
            check(&format!("Content-Length: {len}\r\n\r\n{m}{}", framed(&msg(2))), &[1, 2], true);
            // Alone, with the client waiting for an answer.
            check(&format!("Content-Length: {len}\r\n\r\n{m}"), &[1], true);
        }
        // A header with no length at all.
        check(&format!("Content-Length:\r\n\r\n{}", framed(&msg(2))), &[2], true);
    }

    #[test]
    fn arbitrary_bytes_never_panic() {
        let mut x: u64 = 0x1234_5678;
        for _ in 0..300 {
            let mut bytes = Vec::new();
            for _ in 0..(x % 200) {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let pieces: [&[u8]; 8] = [
                    b"Content-Length: ",
                    b"12",
                    b"\r\n",
                    b"\r\n\r\n",
                    b"{",
                    b"}",
                    b"\"",
                    br#"{"jsonrpc":"2.0","method":"x"}"#,
                ];
                bytes.extend_from_slice(pieces[(x % 8) as usize]);
                bytes.push((x >> 20) as u8);
            }
            let mut f = Framer::new();
            for piece in bytes.chunks(5) {
                f.push(piece);
                while let Some(m) = f.next(false, &mut |_| {}) {
                    assert!(is_jsonrpc(&m));
                }
            }
            while let Some(m) = f.next(true, &mut |_| {}) {
                assert!(is_jsonrpc(&m));
            }
        }
    }
}
