function y = deval(sol, t)
% Octave 7 has no deval: the solution's steps interpolated piecewise-cubically (the
% simulated orbit is only the continuation's first guess, which Newton's method corrects).
y = interp1(sol.x(:), sol.y.', t(:), 'pchip').';
end
