#!/usr/bin/env bash
# Small MAT files written by GNU Octave, for era-io's MAT reader tests
# (crates/era-io/tests/fixtures). 2 outputs x 2 inputs (or 3 x 2), 5 lines at 0.5 Hz;
# FRF(k, (j-1)*q + i) = (k + 5*(col-1)) + 1i*(20 + k + 5*(col-1)).
# Needs: apt-get install -y --no-install-recommends octave
set -euo pipefail
dest=$(cd "$(dirname "$0")/.." && pwd)/crates/era-io/tests/fixtures
mkdir -p "$dest"
cd "$dest"
octave --no-gui -q -H --eval "
FreqV = (0:4)' * 0.5;
FRF = complex(reshape(1:20, 5, 4), reshape(21:40, 5, 4));
save('-v6', 'frf_v6.mat', 'FRF', 'FreqV');
save('-v7', 'frf_v7.mat', 'FRF', 'FreqV');
xfer11 = FRF(:,1); xfer21 = FRF(:,2); xfer12 = FRF(:,3); xfer22 = FRF(:,4);
save('-v7', 'xfer_v7.mat', 'xfer11', 'xfer21', 'xfer12', 'xfer22', 'FreqV');
save('-v7', 'xfer_missing.mat', 'xfer11', 'xfer21', 'xfer12', 'FreqV');
xfer110 = FRF(:,1);
save('-v7', 'xfer_ambiguous.mat', 'xfer110', 'xfer11', 'FreqV');
H = zeros(2, 2, 5);
for i = 1:2, for j = 1:2, H(i,j,:) = FRF(:, (j-1)*2 + i); end, end
save('-v7', 'cube_v7.mat', 'H', 'FreqV');
FRF = complex(reshape(1:30, 5, 6), reshape(31:60, 5, 6));
save('-v7', 'frf_3x2.mat', 'FRF', 'FreqV');
FRF = single(complex(reshape(1:20, 5, 4), reshape(21:40, 5, 4))); FreqV = single(FreqV);
save('-v6', 'frf_single.mat', 'FRF', 'FreqV');
FreqV = [0; 0.5; 1.5; 2; 2.5]; FRF = complex(reshape(1:20, 5, 4), 0);
save('-v7', 'frf_uneven.mat', 'FRF', 'FreqV');
names = {'a', 'b'}; label = 'not numeric';
save('-v7', 'cell_only.mat', 'names', 'label');
T = reshape(sin(0.1 * (1:600)), 200, 3); u = (1:200)';
save('-v7', 'time_two.mat', 'T', 'u');
" 2>/dev/null
ls -la "$dest"
