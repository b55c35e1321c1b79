function r = any(varargin)
% Octave 7's any has no 'all': any(x, 'all') is any(x(:)).
if nargin == 2 && ischar(varargin{2}) && strcmp(varargin{2}, 'all')
  r = builtin('any', varargin{1}(:));
else
  r = builtin('any', varargin{:});
end
end
