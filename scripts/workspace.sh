# Sourced by every script: where the catkin workspace of this checkout lives.
# It is kept outside the repository (the workspace's src/ links back to the checkout, and a
# workspace inside the repository makes rospack's `find` walk that loop on every rosrun).
# UD_WS overrides it; the default is one workspace per checkout under the user's cache.
ud_workspace() {
  local repo="$1"
  if [ -n "${UD_WS:-}" ]; then printf '%s\n' "$UD_WS"; return; fi
  local hash
  hash="$(printf '%s' "$repo" | md5sum | cut -c1-8)"
  printf '%s/urban_detection/ws-%s-%s\n' "${XDG_CACHE_HOME:-$HOME/.cache}" "$(basename "$repo")" "$hash"
}
