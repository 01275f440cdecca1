% Eigenvalues of the thesis routines' model of the peer's DTA-like set (mkdta.m),
% with the thesis DTA settings; called by scripts/octave_peer.sh golden.
% Usage (from the peer's folder): octave --eval "octave_dta_eigs('out.csv')"
function octave_dta_eigs(out)
  [FRF, FreqV] = mkdta();
  p = [8 8 5 80 1 0 -1 3 -1 2 0 1024];
  [a, ~, ~, ~, Ts] = frffilt(FRF, FreqV, p);
  ev = eig(a);
  fid = fopen(out, 'w');
  fprintf(fid, 'sample_time_s,%.17g\nre_z,im_z\n', Ts);
  fprintf(fid, '%.17g,%.17g\n', [real(ev) imag(ev)]');
  fclose(fid);
end
