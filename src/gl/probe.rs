//! Does a window system answer? Connects to the X11 or Wayland socket named
//! by the environment, so `--backend auto` can choose a window only when one
//! can really open. (winit cannot be asked twice: a process gets one event
//! loop, so the probe must not use it.)

use std::net::TcpStream;
use std::os::unix::net::UnixStream;
use std::path::PathBuf;
use std::time::Duration;

/// Where an X11 `DISPLAY` value says the server listens.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum X11Address {
    /// `:N` or `unix:N`: the local socket `/tmp/.X11-unix/XN`.
    Local(PathBuf),
    /// `host:N`: TCP port 6000 + N.
    Tcp(String, u16),
}

/// Parses a `DISPLAY` value (`[host]:display[.screen]`); None when it is
/// not one this probe understands.
pub fn parse_x11_display(display: &str) -> Option<X11Address> {
    let (host, rest) = display.rsplit_once(':')?;
    let number = rest.split('.').next()?;
    let number: u16 = number.parse().ok()?;
    match host {
        "" | "unix" => Some(X11Address::Local(PathBuf::from(format!("/tmp/.X11-unix/X{number}")))),
        host if !host.contains('/') => {
            Some(X11Address::Tcp(host.to_owned(), 6000u16.checked_add(number)?))
        }
        _ => None,
    }
}

/// Where `WAYLAND_DISPLAY` points: an absolute path or a name under
/// `XDG_RUNTIME_DIR`.
pub fn wayland_socket(display: &str, runtime_dir: Option<&str>) -> Option<PathBuf> {
    if display.starts_with('/') {
        return Some(PathBuf::from(display));
    }
    runtime_dir.map(|dir| PathBuf::from(dir).join(display))
}

/// Ok when a Wayland or X11 server accepts a connection; otherwise why not.
pub fn display_answers() -> Result<(), String> {
    let env = |name| std::env::var(name).ok().filter(|value: &String| !value.is_empty());
    let mut tried = Vec::new();
    if env("WAYLAND_SOCKET").is_some() {
        return Ok(());
    }
    if let Some(display) = env("WAYLAND_DISPLAY") {
        let runtime_dir = env("XDG_RUNTIME_DIR");
        match wayland_socket(&display, runtime_dir.as_deref()) {
            Some(path) => match UnixStream::connect(&path) {
                Ok(_) => return Ok(()),
                Err(e) => tried.push(format!("WAYLAND_DISPLAY {}: {e}", path.display())),
            },
            None => tried.push(format!("WAYLAND_DISPLAY={display} without XDG_RUNTIME_DIR")),
        }
    }
    if let Some(display) = env("DISPLAY") {
        match connect_x11(&display) {
            Ok(()) => return Ok(()),
            Err(e) => tried.push(format!("DISPLAY={display}: {e}")),
        }
    }
    if tried.is_empty() {
        tried.push("neither DISPLAY nor WAYLAND_DISPLAY is set".to_owned());
    }
    Err(tried.join("; "))
}

fn connect_x11(display: &str) -> Result<(), String> {
    match parse_x11_display(display) {
        Some(X11Address::Local(path)) => {
            UnixStream::connect(&path).map(drop).map_err(|e| format!("{}: {e}", path.display()))
        }
        Some(X11Address::Tcp(host, port)) => {
            let addr = std::net::ToSocketAddrs::to_socket_addrs(&(host.as_str(), port))
                .map_err(|e| format!("{host}: {e}"))?
                .next()
                .ok_or_else(|| format!("{host} has no address"))?;
            TcpStream::connect_timeout(&addr, Duration::from_secs(1))
                .map(drop)
                .map_err(|e| format!("{host}:{port}: {e}"))
        }
        None => Err("not a DISPLAY value this probe understands".to_owned()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_local_and_remote_displays() {
        let local =
            |n: &str| Some(X11Address::Local(PathBuf::from(format!("/tmp/.X11-unix/X{n}"))));
        assert_eq!(parse_x11_display(":0"), local("0"));
        assert_eq!(parse_x11_display(":99.0"), local("99"));
        assert_eq!(parse_x11_display("unix:3"), local("3"));
        assert_eq!(parse_x11_display("box:1.0"), Some(X11Address::Tcp("box".into(), 6001)));
        assert_eq!(parse_x11_display("0"), None);
        assert_eq!(parse_x11_display(":x"), None);
        assert_eq!(parse_x11_display(":70000"), None);
        assert_eq!(parse_x11_display("/private/tmp/launchd/org.xquartz:0"), None);
    }

    #[test]
    fn finds_wayland_sockets() {
        assert_eq!(wayland_socket("/run/w", None), Some(PathBuf::from("/run/w")));
        assert_eq!(
            wayland_socket("wayland-0", Some("/run/user/1")),
            Some(PathBuf::from("/run/user/1/wayland-0"))
        );
        assert_eq!(wayland_socket("wayland-0", None), None);
    }
}
