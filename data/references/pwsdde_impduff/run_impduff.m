% Headless driver for PWSDDE-cont's 2-DOF impact Duffing demo (impd_osc_demo.m): the same
% calls in the same order, the figures left out, every branch's points and events written to
% CSV. Set the checkout's root, the Chebyshev mesh M and an output directory beforehand:
%   octave --no-gui --no-window-system --eval \
%     "root='/tmp/pws'; M=20; out='/tmp/pwsrun/M20'; run('/tmp/pwsrun/run_impduff.m')"
% With `upto = 2` set too, only the demo's first two runs (from omega = 1.5 and 0.7) are made.
% The shims of octave_shim/ (deval, and the 'all' of any and max, strfind of []) stand in for
% MATLAB behaviour Octave 7 lacks; see PROVENANCE.md.
warning off backtrace
warning('off', 'all');
cd(root); addpath(fullfile(fileparts(mfilename('fullpath')), 'octave_shim'));
set(0, 'DefaultFigureVisible', 'off');
if ~exist('upto', 'var'), upto = 6; end
addpath(genpath('_toolbox'))
addpath(genpath('pwsdde cont'))
addpath('_system def/two dof impact oscillator');
impduff_def;
sys = struct2func(struct);
mkdir(out);

p0 = [1.5 1.0 1.0 0.05 0.9 0.02 0.127 0.952 0.1 0.1];
y0 = @(t) [0; 0; 0; 0; 1; 0];
o_init.N = 2;
o_init.M = M;
sim_opts.t_end = 150*pi/p0(1);
sim_opts.h_act = [1 1 0 0];
[orb0,res] = sim_ns_dde(y0,p0,sys,o_init,sim_opts);
p0(1) = 0.7; sim_opts.t_end = 150*pi/p0(1);
[orb1,res] = sim_ns_dde(y0,p0,sys,o_init,sim_opts);

t0 = tic;
opts1 = br12_opts(1);
branch1 = br12_cont_adapt(orb0,sys,opts1);
opts2 = br12_opts(1);
branch2 = br12_cont_adapt(orb1,sys,opts2);
branches = {branch1, branch2};
if upto > 2

[~,~,~,~,ibif] = get_br_data(branch1,opts1.pi);
pert_opts.type = 2;
orbpd = bif_orb_perturb(branch1(ibif.i_sc(1)),sys,pert_opts);
psa_opts = br12_opts(1,1e-5);
orbpdc = orb_corr_psa(orbpd,sys,psa_opts);
opts3 = opts1;
branch3 = br12_cont_adapt(orbpdc,sys,opts3);

[~,~,~,~,ibif] = get_br_data(branch2,opts2.pi);
pert_opts.type = 2;
orbpd = bif_orb_perturb(branch2(ibif.i_sc(2)),sys,pert_opts);
psa_opts = br12_opts(1,1e-5);
orbpdc = orb_corr_psa(orbpd,sys,psa_opts);
opts4 = opts1;
branch4 = br12_cont_adapt(orbpdc,sys,opts4);

t_guess = [0.0 2.100 3.451 4.620];
orbgr = orb_convert(branch3(end),sys,t_guess);
opts5 = opts3; opts5.stop.ext_gr = false;
branch5 = br12_cont_adapt(orbgr,sys,opts5);

t_guess = [0.0 2.859 4.617 5.980];
orbgr = orb_convert(branch4(end),sys,t_guess);
opts6 = opts4; opts6.stop.ext_gr = false;
branch6 = br12_cont_adapt(orbgr,sys,opts6);
branches = {branch1, branch2, branch3, branch4, branch5, branch6};
end
cpu = toc(t0);

% One row a point: omega, x1's half peak-to-peak on a 2000-point resampling of the orbit, the
% period, the critical multiplier and the solver's event text.
fid = fopen(fullfile(out, 'points.csv'), 'w');
fprintf(fid, 'branch,index,omega,amp_x1,max_x1,min_x1,period,mu_crit_re,mu_crit_im,abs_mu_crit,n_events,event\n');
for b = 1:numel(branches)
  br = branches{b};
  for i = 1:numel(br)
    [~,u] = bvp2sig(br(i).U, br(i).T, br(i).M, 2000);
    mc = br(i).mu_crit; if isempty(mc), mc = NaN; end
    ev = br(i).bif_type; if isempty(ev), ev = ''; end
    ev = strrep(ev, ',', ';');
    fprintf(fid, '%d,%d,%.15g,%.15g,%.15g,%.15g,%.15g,%.15g,%.15g,%.15g,%d,%s\n', b, i, br(i).p(1), ...
      (max(u(1,:))-min(u(1,:)))/2, max(u(1,:)), min(u(1,:)), sum(br(i).T), real(mc), imag(mc), abs(mc), ...
      numel(br(i).sig), ev);
  end
end
fclose(fid);
fid = fopen(fullfile(out, 'run.txt'), 'w');
fprintf(fid, 'octave %s\nM %d\ncontinuation seconds (wall, tic/toc) %.1f\ncputime %.1f\n', version(), M, cpu, cputime());
fclose(fid);
