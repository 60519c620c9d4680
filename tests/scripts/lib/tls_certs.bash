# Sourced by the TLS script tests: a throwaway CA and certificates made with openssl(1).
#
#   tls_prologue
# What every TLS script begins with: $work, a folder removed at exit (kept when KEEP_WORK is
# set) with the server stopped, the certificates below made in it, and $tls, the client's
# options for them (--transport tls --tls-ca ...). Fails the script when openssl cannot.
tls_prologue() {
  work=$(mktemp -d)
  trap 'stop_server; [ -n "${KEEP_WORK:-}" ] || rm -rf "$work"' EXIT
  make_tls_certs "$work" || { echo "FAIL: openssl could not make the certificates"; exit 1; }
  tls=(--transport tls --tls-ca "$work/ca.pem")
}

#   make_tls_certs DIR
# Writes into DIR: ca.pem (the CA), server.pem/.key (127.0.0.1), operator.pem/.key and
# viewer.pem/.key (clients whose Modbus/TCP Security role extension, OID
# 1.3.6.1.4.1.50316.802.1, says Operator or Viewer), norole.pem/.key (a client of the same CA
# without a role), trailing.pem/.key (a client whose role extension holds the UTF8String
# "Operator" and two bytes after it: not a role) and rogue.pem/.key (a client with a role,
# signed by another CA).
make_tls_certs() {
  local d=$1 name
  openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 \
    -subj /CN=mbstorm-test-ca -keyout "$d/ca.key" -out "$d/ca.pem" 2>/dev/null || return 1
  openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 \
    -subj /CN=rogue-ca -keyout "$d/rogue-ca.key" -out "$d/rogue-ca.pem" 2>/dev/null || return 1
  cat >"$d/ext.cnf" <<'CNF'
[server]
basicConstraints = CA:FALSE
subjectAltName = IP:127.0.0.1, DNS:localhost
extendedKeyUsage = serverAuth
[operator]
basicConstraints = CA:FALSE
extendedKeyUsage = clientAuth
1.3.6.1.4.1.50316.802.1 = ASN1:UTF8String:Operator
[viewer]
basicConstraints = CA:FALSE
extendedKeyUsage = clientAuth
1.3.6.1.4.1.50316.802.1 = ASN1:UTF8String:Viewer
[norole]
basicConstraints = CA:FALSE
extendedKeyUsage = clientAuth
[trailing]
basicConstraints = CA:FALSE
extendedKeyUsage = clientAuth
1.3.6.1.4.1.50316.802.1 = DER:0C:08:4F:70:65:72:61:74:6F:72:FF:FF
CNF
  # name section signing-CA
  for spec in "server server ca" "operator operator ca" "viewer viewer ca" \
              "norole norole ca" "trailing trailing ca" "rogue operator rogue-ca"; do
    set -- $spec
    name=$1
    openssl req -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes \
      -subj "/CN=$name" -keyout "$d/$name.key" -out "$d/$name.csr" 2>/dev/null || return 1
    openssl x509 -req -in "$d/$name.csr" -CA "$d/$3.pem" -CAkey "$d/$3.key" -CAcreateserial \
      -days 2 -extfile "$d/ext.cnf" -extensions "$2" -out "$d/$name.pem" 2>/dev/null || return 1
  done
}
